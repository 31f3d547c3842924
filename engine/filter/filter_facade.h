// What every model's public facade does around its engine, written once: Create() (validate,
// check the ranks, pick the threads, build without letting an exception out), Checkpoint() and
// Resume() (the file head, the configuration block, the rank record, the user data and the
// driver's state around the model's own body), and the read-outs of one particle or of sums
// over every particle across ranks. A model's facade writes only its body and its read-outs.
//
// A checkpoint body, in order (engine/io/checkpoint_io.h gives the sealed file around it):
//   head     kind, configuration hash and field block, user data (WriteCheckpointHead)
//   rank     this rank and the rank count (WriteCheckpointRank)
//   driver   times, mean poses, the filter's weights and counters (FilterDriver::Save)
//   model    the model's own state (its SaveBody)
//   u32      kCheckpointEndMarker
#ifndef GROVE_ENGINE_FILTER_FILTER_FACADE_H_
#define GROVE_ENGINE_FILTER_FILTER_FACADE_H_

#include <algorithm>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <thread>
#include <utility>
#include <vector>

#include "engine/filter/filter_driver.h"
#include "engine/filter/resampler.h"
#include "engine/io/checkpoint_io.h"
#include "engine/ranks/collective.h"
#include "grove/config_fields.h"
#include "grove/status.h"

namespace grove {

// How a model's checkpoints are told apart.
struct CheckpointFormat {
  const char* kind;   // the body's first string ("grove footslam")
  const char* model;  // the model's name in messages ("FootSLAM")
  uint32_t version;   // the body's layout, bumped whenever it changes
};

// The worker threads for a configuration's `threads`: itself, or one per hardware thread for 0.
inline int WorkerThreads(int threads) {
  return threads > 0 ? threads : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

// Facade::Create(config, ranks): validates `config`, checks it for the ranks
// (Facade::CheckAcrossRanks; `ranks` null or of one rank: one process) and returns
// make(threads, ranks) -> StatusOr<std::unique_ptr<Facade>>, with ranks null for one process;
// an exception becomes a status.
template <typename Facade, typename Config, typename Make>
StatusOr<std::unique_ptr<Facade>> CreateFacade(const Config& config, Collective* ranks,
                                               Make&& make) {
  GROVE_RETURN_IF_ERROR(config.Validate());
  if (ranks != nullptr && ranks->size() > 1) {
    GROVE_RETURN_IF_ERROR(Facade::CheckAcrossRanks(config, ranks->size()));
  } else {
    ranks = nullptr;
  }
  return NoThrow([&]() -> StatusOr<std::unique_ptr<Facade>> {
    return make(WorkerThreads(config.threads), ranks);
  });
}

// A whole checkpoint file of an engine: the head, the rank record, the driver's state, then
// save_body(ByteWriter*) and the end marker, sealed. FailedPrecondition after an error stopped
// the engine.
template <typename Config, typename Model, typename SaveBody>
StatusOr<std::string> SaveCheckpoint(const CheckpointFormat& format,
                                     const std::vector<ConfigField<Config>>& fields,
                                     const Config& config, const Collective* ranks,
                                     const FilterDriver<Model>& driver, std::string_view user_data,
                                     SaveBody&& save_body) {
  GROVE_RETURN_IF_ERROR(driver.CheckNotFailed("there is no state to save"));
  ByteWriter w;
  WriteCheckpointHead(&w, format.kind, CheckpointFieldsOf(fields, config), user_data);
  // Across ranks, each rank saves its own share: which share it is comes first.
  WriteCheckpointRank(&w, ranks);
  driver.Save(&w);
  save_body(&w);
  w.Put<uint32_t>(kCheckpointEndMarker);
  return SealCheckpoint(w.Take(), format.version);
}

// Reads what SaveCheckpoint() wrote after the head into a new engine: the rank record, the
// driver's state, load_body(ByteReader*) -> Status, and the end marker, which must end the body.
template <typename Model, typename LoadBody>
Status LoadCheckpoint(ByteReader* r, const Collective* ranks, FilterDriver<Model>* driver,
                      LoadBody&& load_body) {
  GROVE_RETURN_IF_ERROR(ReadCheckpointRank(r, ranks));
  GROVE_RETURN_IF_ERROR(driver->Load(r));
  GROVE_RETURN_IF_ERROR(load_body(r));
  uint32_t end = 0;
  GROVE_RETURN_IF_ERROR(r->Get("end marker", &end));
  if (end != kCheckpointEndMarker || !r->at_end()) {
    return r->Error("end marker", "missing, or bytes follow it");
  }
  return Status::Ok();
}

// A facade's Resume() across ranks (collective): resume_share(ranks) on every rank, whose
// errors then reach every rank, and the ranks' files must be of one step (CheckCheckpointSteps).
// Without ranks, or with one, resume_share(nullptr).
template <typename Engine, typename F>
StatusOr<std::unique_ptr<Engine>> ResumeOnRanks(Collective* ranks, F&& resume_share) {
  if (ranks == nullptr || ranks->size() == 1) return resume_share(nullptr);
  StatusOr<std::unique_ptr<Engine>> engine = resume_share(ranks);
  GROVE_RETURN_IF_ERROR(AgreeStatus(*ranks, engine.status()));
  GROVE_RETURN_IF_ERROR(CheckCheckpointSteps(*ranks, (*engine)->steps()));
  return engine;
}

// Facade::Resume(config, checkpoint, name, user_data, ranks): on each rank, validates `config`,
// checks the file's seal, kind, format version and configuration block before any engine is
// built, then creates the engine (Facade::Create(config, ranks)) and has
// load(Facade&, ByteReader*) -> Status (LoadCheckpoint) read the rest; across ranks, any
// rank's error reaches every rank and the files must be of one step (ResumeOnRanks).
template <typename Facade, typename Config, typename Load>
StatusOr<std::unique_ptr<Facade>> ResumeFacade(const CheckpointFormat& format,
                                               const std::vector<ConfigField<Config>>& fields,
                                               const Config& config, std::string_view checkpoint,
                                               const std::string& name, std::string* user_data,
                                               Collective* ranks, Load&& load) {
  auto resume_share = [&](Collective* share_ranks) -> StatusOr<std::unique_ptr<Facade>> {
    GROVE_RETURN_IF_ERROR(config.Validate());
    return NoThrow([&]() -> StatusOr<std::unique_ptr<Facade>> {
      StatusOr<UnsealedCheckpoint> file = UnsealCheckpoint(checkpoint, name);
      if (!file.ok()) return file.status();
      ByteReader reader(file->body, name);
      // The kind, format and configuration first: a checkpoint of another run costs no engine.
      std::string user;
      GROVE_RETURN_IF_ERROR(ReadCheckpointHead(&reader, format.kind, format.model,
                                               file->format_version, format.version,
                                               CheckpointFieldsOf(fields, config), &user));
      StatusOr<std::unique_ptr<Facade>> engine = Facade::Create(config, share_ranks);
      if (!engine.ok()) return engine.status();
      GROVE_RETURN_IF_ERROR(load(**engine, &reader));
      if (user_data != nullptr) user_data->swap(user);
      return engine;
    });
  };
  return ResumeOnRanks<Facade>(ranks, resume_share);
}

// The value of(i) of the particle `global` (a global index: FilterDriver's heaviest()), from
// the rank of `share` that holds it; `fallback` when the ranks fail to exchange it.
// Collective across ranks (null: one process).
template <typename T, typename Of>
T FromHolder(Collective* ranks, const ParticleShare& share, size_t local_count, size_t global,
             Of&& of, const T& fallback) {
  std::vector<T> mine;
  if (global >= share.first && global - share.first < local_count) {
    mine.push_back(of(global - share.first));
  }
  StatusOr<std::vector<T>> all = GatherOverRanks(ranks, std::move(mine));
  return all.ok() && all->size() == 1 ? all->front() : fallback;
}

// sum(begin, end) -> Sum over fixed blocks of kSumBlock particles, every rank's blocks in
// order (null `ranks`: this process's), combined by add(Sum*, const Sum&) in that order: the
// same bits at any thread or rank count. Collective.
template <typename Sum, typename SumRange, typename Add>
StatusOr<Sum> SumOverBlocks(Collective* ranks, size_t count, SumRange&& sum, Add&& add) {
  std::vector<Sum> blocks;
  for (size_t b = 0; b < count; b += kSumBlock) {
    blocks.push_back(sum(b, std::min(count, b + kSumBlock)));
  }
  StatusOr<std::vector<Sum>> all = GatherOverRanks(ranks, std::move(blocks));
  if (!all.ok()) return all.status();
  Sum total{};
  for (const Sum& block : *all) add(&total, block);
  return total;
}

}  // namespace grove

#endif  // GROVE_ENGINE_FILTER_FILTER_FACADE_H_
