// WriteParticles and ReadParticles: the message that moves particles of a MigratingModel between
// ranks or islands at a resampling, and MigrationStats, what moving them cost.
#ifndef GROVE_ENGINE_FILTER_PARTICLE_MIGRATION_H_
#define GROVE_ENGINE_FILTER_PARTICLE_MIGRATION_H_

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "engine/filter/filter_model.h"
#include "engine/io/checkpoint_io.h"
#include "grove/status.h"

namespace grove {

// Summed over a filter's resamplings.
struct MigrationStats {
  uint64_t sent_bytes = 0;      // bytes of particles this rank sent to other ranks
  uint64_t sent_particles = 0;  // distinct particles in them
  double migrate_s = 0;         // writing and reading the particles that move (not sending them)
};

// A message of particles that move: `which` (local indices of `model`) with their copy counts,
// then the particles as the model exports them.
template <MigratingModel Model>
std::string WriteParticles(const Model& model, std::span<const uint32_t> which,
                           std::span<const uint32_t> copies) {
  ByteWriter w;
  w.Put<uint64_t>(which.size());
  w.PutBytes(copies.data(), copies.size_bytes());
  model.Export(which, &w);
  return w.Take();
}

// Imports the particles of a WriteParticles() message named `name` into `model` (paths no newer
// than `step`) and appends their copies, as the model's new indices, to *parents (at most
// `limit` in all, each particle at least one); *copies_read is their sum.
template <MigratingModel Model>
Status ReadParticles(Model* model, std::string_view bytes, const std::string& name, uint64_t step,
                     uint64_t limit, std::vector<uint32_t>* parents, uint64_t* copies_read) {
  ByteReader r(bytes, name);
  uint64_t count = 0;
  GROVE_RETURN_IF_ERROR(r.GetCount("particle count", sizeof(uint32_t), &count));
  std::vector<uint32_t> copies(count);
  GROVE_RETURN_IF_ERROR(r.GetBytes("copies", copies.data(), count * sizeof(uint32_t)));
  const size_t base = model->size();
  GROVE_RETURN_IF_ERROR(model->Import(&r, count, step));
  if (!r.at_end()) return r.Error("end", "bytes after the particles");
  uint64_t total = 0;
  for (size_t k = 0; k < count; ++k) {
    total += copies[k];
    if (copies[k] == 0 || total > limit) {
      return r.Error("copies", "more copies than the slots they fill");
    }
    parents->insert(parents->end(), copies[k], static_cast<uint32_t>(base + k));
  }
  *copies_read = total;
  return Status::Ok();
}

}  // namespace grove

#endif  // GROVE_ENGINE_FILTER_PARTICLE_MIGRATION_H_
