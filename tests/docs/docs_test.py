#!/usr/bin/python3
"""Runs the documentation's examples against a build, so that a change that breaks one fails.

- README.md: every ```sh block under "## Quick start", in order, each as one bash script with
  `set -euo pipefail`, in a fresh directory that stands for the repository root (the source
  tree's entries are linked into it, and `build` is the build directory); HOME is a directory of
  its own, so installs into "$HOME/..." stay in the test. Blocks that call mpirun run only with
  --mpiexec (an `mpirun` on PATH then starts ranks oversubscribed); blocks that call python3 run
  only with --python.
- engine/include/grove/README.md: every ```cpp and ```c block is a whole program, compiled
  against the source tree's public headers and the build's libgrove.so and run; every ```python
  block runs with the build's module on PYTHONPATH (only with --python).

Usage: docs_test.py SOURCE_DIR BUILD_DIR [--python] [--mpiexec MPIEXEC]
"""

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile

# The least the README's quick start holds: a block per use (FootSLAM, landmark FastSLAM,
# embedding, batches and ranks, benchmarks). Fewer means the section was broken or renamed.
MIN_QUICK_START_BLOCKS = 5


def blocks(text, languages):
    """(language, code, line) of every fenced block whose language is in `languages`."""
    found = []
    for m in re.finditer(r"^```(\w+)\n(.*?)^```$", text, re.S | re.M):
        if m.group(1) in languages:
            found.append((m.group(1), m.group(2), text.count("\n", 0, m.start()) + 1))
    return found


def section(text, heading):
    """The text under `heading` (a "## " line) up to the next "## " heading."""
    m = re.search(r"^" + re.escape(heading) + r"\n(.*?)(?=^## |\Z)", text, re.S | re.M)
    return m.group(1) if m else None


def run(what, command, cwd, env, failures, shown=""):
    print(f"--- {what}\n{shown}", end="", flush=True)
    result = subprocess.run(command, cwd=cwd, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)
    print(result.stdout[-3000:], end="")
    if result.returncode != 0:
        failures.append(f"{what}: exit {result.returncode}")
        print(f"FAIL: {what} exited {result.returncode}", flush=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("source")
    ap.add_argument("build")
    ap.add_argument("--python", action="store_true")
    ap.add_argument("--mpiexec")
    args = ap.parse_args()
    source, build = os.path.abspath(args.source), os.path.abspath(args.build)
    failures = []
    work = tempfile.mkdtemp(prefix="grove_docs_test_")
    try:
        root = os.path.join(work, "repo")
        home = os.path.join(work, "home")
        tools_bin = os.path.join(work, "bin")
        for d in (root, home, tools_bin):
            os.mkdir(d)
        for name in os.listdir(source):
            if name not in ("build", ".git"):
                os.symlink(os.path.join(source, name), os.path.join(root, name))
        os.symlink(build, os.path.join(root, "build"))
        env = dict(os.environ, HOME=home, PYTHONDONTWRITEBYTECODE="1", MPLBACKEND="Agg",
                   OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
        if args.mpiexec:
            wrapper = os.path.join(tools_bin, "mpirun")
            with open(wrapper, "w") as f:
                f.write(f'#!/bin/sh\nexec "{args.mpiexec}" --oversubscribe --bind-to none "$@"\n')
            os.chmod(wrapper, 0o755)
            env["PATH"] = tools_bin + os.pathsep + env.get("PATH", "")

        readme = open(os.path.join(source, "README.md")).read()
        quick = section(readme, "## Quick start")
        if quick is None:
            sys.exit('FAIL: README.md has no "## Quick start" section')
        shell = blocks(quick, {"sh"})
        if len(shell) < MIN_QUICK_START_BLOCKS:
            sys.exit(f"FAIL: README.md's quick start has {len(shell)} sh blocks, expected at "
                     f"least {MIN_QUICK_START_BLOCKS}")
        for k, (_, code, line) in enumerate(shell):
            what = f"README.md quick-start block {k + 1} (line {line} of the section)"
            if "mpirun" in code and not args.mpiexec:
                print(f"--- {what}: skipped (built without MPI)")
                continue
            if "python3" in code and not args.python:
                print(f"--- {what}: skipped (built without the Python module)")
                continue
            run(what, ["bash", "-c", "set -euo pipefail\n" + code], root, env, failures, code)

        embedding = open(os.path.join(source, "engine/include/grove/README.md")).read()
        examples = blocks(embedding, {"cpp", "c", "python"})
        if not any(lang == "cpp" for lang, _, _ in examples):
            sys.exit("FAIL: engine/include/grove/README.md has no C++ example")
        lib = os.path.join(build, "engine")
        include = os.path.join(source, "engine", "include")
        for k, (lang, code, line) in enumerate(examples):
            what = f"engine/include/grove/README.md {lang} example at line {line}"
            program = os.path.join(work, f"example{k}")
            if lang == "python":
                if not args.python:
                    print(f"--- {what}: skipped (built without the Python module)")
                    continue
                with open(program + ".py", "w") as f:
                    f.write(code)
                run(what, ["/usr/bin/python3", program + ".py"], root,
                    dict(env, PYTHONPATH=os.path.join(build, "python")), failures)
                continue
            suffix, compiler = (".cc", ["c++", "-std=c++20"]) if lang == "cpp" else (
                ".c", ["cc", "-std=c99", "-pedantic"])
            with open(program + suffix, "w") as f:
                f.write(code)
            before = len(failures)
            run(what + ": compile", compiler + ["-Wall", "-Werror", "-I", include,
                                                program + suffix, "-o", program, "-L", lib,
                                                "-lgrove", "-Wl,-rpath," + lib], work, env,
                failures)
            if len(failures) == before:
                run(what + ": run", [program], root, env, failures)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    if failures:
        print("FAILED:\n  " + "\n  ".join(failures))
        sys.exit(1)
    print("docs test passed")


if __name__ == "__main__":
    main()
