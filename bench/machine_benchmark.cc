// The machine's own thread scaling: one thread against two (or more) on work that shares nothing,
// from pure arithmetic to random reads, dependent loads and read-modify-writes over a working set
// per thread that fits a core's L2, fits the shared L3 with the other threads', or only main
// memory. Each thread has a set of the same size whatever the thread count, in huge pages as the
// node pools' slabs are, so two threads differ from one only by what the cores share (the L3, the
// memory controller, the host). One more case shares on purpose: locked increments on one set
// that every thread uses, the price of a line that moves between the cores, and the round trip of
// one line between two threads, the latency of such a move. No engine code runs
// here: the figures say what the machine gives a second thread, the ceiling for the engine's own
// 2-thread scaling.
//
// Rates are accesses per second summed over threads (items_per_second); the CPU column is the
// whole process's CPU time per iteration (MeasureProcessCPUTime).
#include <benchmark/benchmark.h>
#include <sys/mman.h>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>
#include <numeric>
#include <vector>

namespace grove {
namespace {

constexpr int kAccessesPerIteration = 4096;

// SplitMix64's finaliser: a few multiplies and shifts, the kind of arithmetic a random draw does.
uint64_t Mix(uint64_t x) {
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ULL;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// Each thread's random stream starts far from the others'.
uint64_t ThreadSeed(const benchmark::State& state) {
  return static_cast<uint64_t>(state.thread_index()) << 40;
}

struct alignas(64) Line {
  uint64_t word[8];
};

struct FreeDeleter {
  void operator()(Line* p) const { std::free(p); }
};

// This thread's working set of state.range(0) KiB (a power of two), zeroed, in 2 MiB-aligned
// memory advised for huge pages.
class Set {
 public:
  explicit Set(const benchmark::State& state)
      : lines_(static_cast<size_t>(state.range(0)) * 1024 / sizeof(Line)) {
    const size_t bytes = lines_ * sizeof(Line);
    const size_t huge = size_t{2} << 20;
    lines_ptr_.reset(
        static_cast<Line*>(std::aligned_alloc(huge, (bytes + huge - 1) / huge * huge)));
    if (lines_ptr_ == nullptr) throw std::bad_alloc();
#ifdef MADV_HUGEPAGE
    madvise(lines_ptr_.get(), bytes, MADV_HUGEPAGE);
#endif
    std::memset(lines_ptr_.get(), 0, bytes);
  }
  size_t lines() const { return lines_; }
  Line& operator[](size_t i) { return lines_ptr_[i]; }

 private:
  size_t lines_;
  std::unique_ptr<Line[], FreeDeleter> lines_ptr_;
};

void BM_MachineArithmetic(benchmark::State& state) {
  uint64_t x = ThreadSeed(state) + 1;
  for (auto _ : state) {
    for (int i = 0; i < kAccessesPerIteration; ++i) x = Mix(x);
    benchmark::DoNotOptimize(x);
  }
  state.SetItemsProcessed(state.iterations() * kAccessesPerIteration);
}
BENCHMARK(BM_MachineArithmetic)->Threads(1)->Threads(2)->UseRealTime()->MeasureProcessCPUTime();

// Independent random reads: many misses in flight at once (bandwidth and queueing).
void BM_MachineRandomRead(benchmark::State& state) {
  Set set(state);
  const size_t lines = set.lines();
  for (size_t i = 0; i < lines; ++i) set[i].word[0] = i;
  uint64_t seed = ThreadSeed(state);
  uint64_t sum = 0;
  for (auto _ : state) {
    for (int i = 0; i < kAccessesPerIteration; ++i) sum += set[Mix(seed++) & (lines - 1)].word[0];
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(state.iterations() * kAccessesPerIteration);
}

// Dependent random loads, one miss at a time (a tree walk): a single cycle through every line
// (Sattolo's shuffle), so the next address is known only once the load returns.
void BM_MachinePointerChase(benchmark::State& state) {
  Set set(state);
  const size_t lines = set.lines();
  std::vector<uint64_t> order(lines);
  std::iota(order.begin(), order.end(), uint64_t{0});
  uint64_t seed = ThreadSeed(state);
  for (size_t i = lines - 1; i > 0; --i) std::swap(order[i], order[Mix(seed++) % i]);
  for (size_t i = 0; i < lines; ++i) set[order[i]].word[0] = order[(i + 1) % lines];
  uint64_t at = order[0];
  for (auto _ : state) {
    for (int i = 0; i < kAccessesPerIteration; ++i) at = set[at].word[0];
    benchmark::DoNotOptimize(at);
  }
  state.SetItemsProcessed(state.iterations() * kAccessesPerIteration);
}

// Independent random read-modify-writes (a reference count or a node header): every line touched
// comes back dirty, so it costs a write-back as well as a fill.
void BM_MachineRandomIncrement(benchmark::State& state) {
  Set set(state);
  const size_t lines = set.lines();
  uint64_t seed = ThreadSeed(state);
  for (auto _ : state) {
    for (int i = 0; i < kAccessesPerIteration; ++i) ++set[Mix(seed++) & (lines - 1)].word[0];
    benchmark::ClobberMemory();
  }
  benchmark::DoNotOptimize(&set[0]);
  state.SetItemsProcessed(state.iterations() * kAccessesPerIteration);
}

// One iteration's locked increments of random lines of `set`.
void LockedIncrements(Set& set, uint64_t* seed) {
  const size_t lines = set.lines();
  for (int i = 0; i < kAccessesPerIteration; ++i) {
    std::atomic_ref<uint64_t>(set[Mix((*seed)++) & (lines - 1)].word[0])
        .fetch_add(1, std::memory_order_relaxed);
  }
}

// Independent random locked increments, each thread on its own set: the lock prefix's price.
void BM_MachineAtomicIncrement(benchmark::State& state) {
  Set set(state);
  uint64_t seed = ThreadSeed(state);
  for (auto _ : state) LockedIncrements(set, &seed);
  state.SetItemsProcessed(state.iterations() * kAccessesPerIteration);
}

// The same locked increments on one set that every thread shares, as the reference counts of
// nodes shared by particles on both cores are: a line the other core changed last must come back
// from its cache. Two threads rarely want one line at the same moment; the cost is the moves.
std::unique_ptr<Set> shared_set;

void BM_MachineSharedAtomicIncrement(benchmark::State& state) {
  // Thread 0 sets the set up before, and frees it after, the loop; every thread meets the others
  // at the loop's start and end.
  if (state.thread_index() == 0) shared_set = std::make_unique<Set>(state);
  uint64_t seed = ThreadSeed(state);
  for (auto _ : state) LockedIncrements(*shared_set, &seed);
  state.SetItemsProcessed(state.iterations() * kAccessesPerIteration);
  if (state.thread_index() == 0) shared_set.reset();
}

// One line handed back and forth between two threads: each iteration is a round trip (the
// `round_trip` counter, in seconds; the time columns count both threads' iterations), the
// latency of a line the other core changed last (what every shared reference-count update can
// wait for). On a virtual machine it depends on where the host placed the two virtual CPUs.
alignas(64) std::atomic<uint64_t> baton{0};

void BM_MachineLineRoundTrip(benchmark::State& state) {
  const bool first = state.thread_index() == 0;
  // Thread 0 resets the baton before the loop; the threads meet at the loop's start.
  if (first) baton.store(0, std::memory_order_relaxed);
  uint64_t turn = 0;
  for (auto _ : state) {
    if (first) {
      baton.store(turn + 1, std::memory_order_release);
      while (baton.load(std::memory_order_acquire) != turn + 2) {
      }
    } else {
      while (baton.load(std::memory_order_acquire) != turn + 1) {
      }
      baton.store(turn + 2, std::memory_order_release);
    }
    turn += 2;
  }
  // Seconds per round trip (thread 1 adds nothing to the threads' sum).
  state.counters["round_trip"] =
      benchmark::Counter(first ? static_cast<double>(state.iterations()) : 0,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_MachineLineRoundTrip)->Threads(2)->UseRealTime();

// Working set per thread in KiB (for the shared set, its whole size): within one core's L2 (2 MiB
// on the development machines), within the shared L3 (32 MiB) with another thread's, and far
// beyond it.
void Sets(benchmark::internal::Benchmark* b) {
  b->ArgName("kib_per_thread");
  for (int64_t kib : {1024, 8 * 1024, 128 * 1024}) b->Arg(kib);
  b->Threads(1)->Threads(2)->UseRealTime()->MeasureProcessCPUTime();
}
BENCHMARK(BM_MachineRandomRead)->Apply(Sets);
BENCHMARK(BM_MachinePointerChase)->Apply(Sets);
BENCHMARK(BM_MachineRandomIncrement)->Apply(Sets);
BENCHMARK(BM_MachineAtomicIncrement)->Apply(Sets);
BENCHMARK(BM_MachineSharedAtomicIncrement)->Apply(Sets);

}  // namespace
}  // namespace grove
