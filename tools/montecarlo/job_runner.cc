#include "tools/montecarlo/job_runner.h"

#include <fmt/format.h>
#include <oneapi/tbb/task_arena.h>
#include <oneapi/tbb/task_group.h>
#include <time.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <new>

#include "tools/montecarlo/job_record.h"
#include "tools/run/signal_policy.h"
#include "tools/sim/fastslam_simulator.h"

namespace grove::tools {
namespace {

double ThreadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// Simulates the job's run and runs its filter on it, on this thread. Never throws: out of
// memory and other exceptions become the outcome's status. A stop signal (StopRequested())
// ends it at the next scan with *stopped set: the job is not finished.
JobOutcome RunJobFilter(const MonteCarloScenario& scenario, const MonteCarloGroup& group,
                        const MonteCarloJob& job, bool* stopped) {
  BaileySimOptions sim_options = scenario.spec.sim;
  sim_options.seed = job.seed;
  JobOutcome o;
  try {
    StatusOr<BaileySimulation> sim = SimulateBailey(scenario.map, sim_options);
    if (!sim.ok()) {
      o.status = sim.status();
      return o;
    }
    o.truth = sim->truth;
    const FastSlamConfig config =
        MonteCarloJobConfig(scenario, group.filter, group.particles, job.seed);
    const double cpu0 = ThreadCpuSeconds();
    StatusOr<std::unique_ptr<FastSlam>> slam = FastSlam::Create(config);
    if (!slam.ok()) {
      o.status = slam.status();
      return o;
    }
    FastSlam& f = **slam;
    o.status = FeedSimulation(*sim, &f, SIZE_MAX, nullptr, [&](double t) -> Status {
      if (StopRequested()) {
        *stopped = true;
        return FailedPreconditionError("stopped by a signal");
      }
      o.scans.push_back({t, f.MeanPose(), f.PoseCovariance()});
      return Status::Ok();
    });
    o.cpu_s = ThreadCpuSeconds() - cpu0;
    o.steps = f.steps();
    o.trajectory = f.MeanTrajectory();
  } catch (const std::bad_alloc&) {
    o.status = ResourceExhaustedError("out of memory");
  } catch (const std::exception& e) {
    o.status = InternalError(fmt::format("internal error: {}", e.what()));
  }
  return o;
}

}  // namespace

std::vector<size_t> JobsToRun(const std::string& dir, const MonteCarloScenario& scenario,
                              const MonteCarloPlan& plan, size_t rank, int ranks,
                              int64_t* own_jobs) {
  const std::vector<MonteCarloJob>& jobs = plan.jobs;
  std::vector<size_t> todo;
  *own_jobs = 0;
  for (size_t i = rank; i < jobs.size(); i += static_cast<size_t>(ranks)) {
    ++*own_jobs;
    if (!ReadFinishedJob(dir, scenario, plan.groups[jobs[i].group], jobs[i]).ok()) {
      todo.push_back(i);
    }
  }
  // std::sort with the index as tie-break: libstdc++ 12's stable_sort trips clang's deprecation
  // warning.
  std::sort(todo.begin(), todo.end(), [&](size_t a, size_t b) {
    const int64_t pa = plan.groups[jobs[a].group].particles;
    const int64_t pb = plan.groups[jobs[b].group].particles;
    return pa != pb ? pa > pb : a < b;
  });
  return todo;
}

Status RunMonteCarloJobs(const MonteCarloScenario& scenario, const MonteCarloPlan& plan,
                         const std::vector<size_t>& todo, int threads, const std::string& dir,
                         JobProgress* progress) {
  if (todo.empty()) return Status::Ok();
  std::atomic<size_t> next{0};
  std::atomic<bool> stop{false};
  std::mutex error_mu;
  Status write_error;
  auto worker = [&] {
    for (;;) {
      // Relaxed: the counter only hands out distinct indices; the task group's wait publishes
      // the results.
      const size_t i = next.fetch_add(1, std::memory_order_relaxed);
      if (i >= todo.size() || stop.load(std::memory_order_relaxed) || StopRequested()) return;
      const MonteCarloJob& job = plan.jobs[todo[i]];
      const MonteCarloGroup& group = plan.groups[job.group];
      bool stopped = false;
      const JobOutcome outcome = RunJobFilter(scenario, group, job, &stopped);
      if (stopped) return;  // not finished: a rerun runs it
      Status s = WriteJobRecord(dir, scenario, group, job, outcome);
      if (!s.ok()) {
        std::lock_guard<std::mutex> lock(error_mu);
        if (write_error.ok()) write_error = s;
        stop.store(true, std::memory_order_relaxed);
        return;
      }
      progress->JobDone();
    }
  };
  tbb::task_arena arena(threads);
  arena.execute([&] {
    tbb::task_group tasks;
    for (int t = 0; t < threads; ++t) tasks.run(worker);
    tasks.wait();
  });
  return write_error;
}

}  // namespace grove::tools
