// The concepts a particle filter's model satisfies: what ParticleFilter and FilterDriver call on
// it, and the optional phases (releasing in pieces, moving between ranks, predicting, completing,
// a population phase) a model opts into by providing them.
#ifndef GROVE_ENGINE_FILTER_FILTER_MODEL_H_
#define GROVE_ENGINE_FILTER_FILTER_MODEL_H_

#include <concepts>
#include <cstddef>
#include <cstdint>
#include <span>

#include "concurrency/worker_pool.h"
#include "engine/io/checkpoint_io.h"
#include "grove/status.h"

namespace grove {

// A model that gathers its next generation in chunks, in a loop the filter runs in the shape
// of its batches: GatherBegin(parents) before the loop, GatherRange(parents, begin, end) on each
// chunk [c * grain, min((c + 1) * grain, n)), GatherEnd(parents, grain) after it. Each new
// particle's values are then written by the thread that advances it next (WorkerPool's homes),
// not all by the driving thread, whose writes the other threads would fetch from its core.
template <typename M>
concept ChunkGatheringModel = requires(M& m, std::span<const uint32_t> parents, size_t k) {
  { m.GatherBegin(parents) } -> std::same_as<void>;
  { m.GatherRange(parents, k, k) } -> std::same_as<void>;
  { m.GatherEnd(parents, k) } -> std::same_as<void>;
};

// A model that gathers its next generation itself: particle k copies parents[k]
// (nondecreasing); maps are shared.
template <typename M>
concept WholeGatheringModel = requires(M& m, std::span<const uint32_t> parents,
                                       WorkerPool& workers) {
  { m.Gather(parents, workers) } -> std::same_as<void>;
};

// What a model provides (checked where a filter is instantiated): a gather, either kind.
template <typename M>
concept GatheringModel = WholeGatheringModel<M> || ChunkGatheringModel<M>;
template <typename M>
concept FilterModel = GatheringModel<M> && requires(M& m, const M& cm, WorkerPool& workers) {
  { cm.size() } -> std::convertible_to<size_t>;
  // Frees what only the previous generation reached.
  { m.ReleaseDead(workers) } -> std::same_as<void>;
};

// The next generation of `m`: particle k copies parents[k]. A chunk-gathering model's in one
// loop of chunks of `grain` (the filter's batch size), another's by its Gather().
template <typename M>
void GatherGeneration(M& m, std::span<const uint32_t> parents, size_t grain, WorkerPool& workers) {
  if constexpr (ChunkGatheringModel<M>) {
    m.GatherBegin(parents);
    workers.ParallelFor(parents.size(), grain,
                        [&](int, size_t b, size_t e) { m.GatherRange(parents, b, e); });
    m.GatherEnd(parents, grain);
  } else {
    m.Gather(parents, workers);
  }
}

// A model that can free its dead generation in pieces: ReleaseDeadRange(lo, hi, slot) releases
// what the previous generation's particles [lo, min(hi, its size)) held, DeadReleased() ends
// that generation once every piece is released. The filter then frees the dead generation
// during the next advance, each batch first releasing the dead particles among its own
// particles' parents (their relatives, whose nodes it is about to touch): the release's cache
// misses overlap the motion's arithmetic, and the separate release loop and its join go.
template <typename M>
concept PieceReleasingModel = requires(M& m, size_t lo, size_t hi, int slot) {
  { m.ReleaseDeadRange(lo, hi, slot) } -> std::same_as<void>;
  { m.DeadReleased() } -> std::same_as<void>;
};

// A model whose particles can move between ranks: Export() writes particles `which` (local
// indices, increasing) with everything they share written once; Import() appends `count`
// particles so written to the model's own (size() grows by count until the next Gather(), whose
// parents may name them), checking every value, with paths no newer than `step`.
template <typename M>
concept MigratingModel = requires(const M& cm, M& m, std::span<const uint32_t> which, ByteWriter* w,
                                  ByteReader* r, size_t count, uint64_t step) {
  { cm.Export(which, w) } -> std::same_as<void>;
  { m.Import(r, count, step) } -> std::same_as<Status>;
};

// A model that weights `Input`: adds each particle's log-likelihood increment to log_w[i] for i
// in [begin, end) after propagating it; returns the first particle's error (the batch stops).
template <typename M, typename Input>
concept WeightingModel = FilterModel<M> &&
    requires(M& m, const Input& in, uint64_t step, size_t i, int slot, double* log_w) {
  { m.Advance(in, step, i, i, slot, log_w) } -> std::same_as<Status>;
};

// A model that propagates on `Input` without weighting.
template <typename M, typename Input>
concept PredictingModel = FilterModel<M> &&
    requires(M& m, const Input& in, uint64_t step, size_t i, int slot) {
  { m.Predict(in, step, i, i, slot) } -> std::same_as<Status>;
};

// A model with a population phase for `Input`, run once its particles are drawn (after
// Complete(), or after Advance() when the model has no Complete()): Population(input, step,
// workers) may move particles (not their weights) and runs its own parallel loops. A model may
// also say, by a member bool PopulationMoves(const Input&) const, whether it will for an input;
// without it, it is taken to.
template <typename M, typename Input>
concept PopulationModel = requires(M& m, const Input& in, uint64_t step, WorkerPool& workers) {
  { m.Population(in, step, workers) } -> std::same_as<Status>;
};

// A model that completes its update of `Input` after resampling, over every particle:
// Complete(input, step, begin, end, slot). FastSLAM 2.0 weights a particle by its predictive
// likelihood, which does not depend on the pose it then draws, so it resamples first and draws
// after (Bailey's order): copies of one parent draw distinct poses.
template <typename M, typename Input>
concept CompletingModel = requires(M& m, const Input& in, uint64_t step, size_t i, int slot) {
  { m.Complete(in, step, i, i, slot) } -> std::same_as<Status>;
};

// A model whose particles have a planar pose after a step: what FilterDriver reads, besides
// FilterModel, for the weighted-mean pose (x and y in metres, the heading's cosine and sine).
template <typename M>
concept PosedModel = FilterModel<M> && requires(const M& m, size_t i) {
  { m.x(i) } -> std::convertible_to<double>;
  { m.y(i) } -> std::convertible_to<double>;
  { m.cos_heading(i) } -> std::convertible_to<double>;
  { m.sin_heading(i) } -> std::convertible_to<double>;
};

}  // namespace grove

#endif  // GROVE_ENGINE_FILTER_FILTER_MODEL_H_
