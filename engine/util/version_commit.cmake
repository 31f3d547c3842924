# Writes OUT (version_commit.h) with the commit the sources are at, run on every build so that a
# binary names the commit it was built from, not the one its build directory was configured at;
# "-dirty" when the work tree had changes. OUT is rewritten only when it changes, so an unchanged
# commit rebuilds nothing.
cmake_minimum_required(VERSION 3.25)
execute_process(COMMAND git describe --always --abbrev=7 --dirty WORKING_DIRECTORY ${SOURCE_DIR}
                OUTPUT_VARIABLE commit OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
if(NOT commit)
  set(commit unknown)
endif()
file(WRITE ${OUT}.new "#define GROVE_COMMIT \"${commit}\"\n")
file(COPY_FILE ${OUT}.new ${OUT} ONLY_IF_DIFFERENT)
file(REMOVE ${OUT}.new)
