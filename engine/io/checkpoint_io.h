// Checkpoint bytes: a little-endian writer and a bounds-checked reader, and the sealed file
// format around them (magic, format version, length, CRC-32 of the body).
//
// File layout (every integer little-endian):
//   offset 0   8 bytes  magic: 0x89 'G' 'R' 'O' 'V' 'E' '\r' '\n' (catches text-mode mangling)
//   offset 8   u32      format version of the model's body (each model numbers its own)
//   offset 12  u32      CRC-32 (zlib) of the body
//   offset 16  u64      body length in bytes
//   offset 24  body
// Every body starts with the head written by WriteCheckpointHead(): the kind ("grove
// footslam"), the configuration hash (CRC-32 of the field block), the field block (every
// configuration field that changes results: name, type, value) and the embedder's user data.
// The rank record, the driver's state and the model's own state follow, then an end marker
// (engine/filter/filter_facade.h).
//
// A reader never reads past its end and never trusts a count: every error is a Status naming
// the field and the byte offset, so a corrupt or hostile file cannot crash the process.
#ifndef GROVE_ENGINE_IO_CHECKPOINT_IO_H_
#define GROVE_ENGINE_IO_CHECKPOINT_IO_H_

#include <bit>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <type_traits>
#include <variant>
#include <vector>

#include "grove/config_fields.h"
#include "grove/status.h"

namespace grove {

static_assert(std::endian::native == std::endian::little,
              "checkpoints are written in the host's byte order, which must be little-endian");

inline constexpr size_t kCheckpointHeaderBytes = 24;
// The last field of every body.
inline constexpr uint32_t kCheckpointEndMarker = 0x21444E45;  // "END!"

class ByteWriter {
 public:
  template <typename T>
  void Put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    out_.append(reinterpret_cast<const char*>(&value), sizeof(T));
  }
  void PutBytes(const void* data, size_t size) {
    if (size == 0) return;  // `data` may be null
    out_.append(static_cast<const char*>(data), size);
  }
  void PutString(std::string_view s) {
    Put<uint64_t>(s.size());
    out_.append(s);
  }
  // Writes a placeholder for a value known later; Patch() fills it in.
  template <typename T>
  size_t Reserve() {
    size_t at = out_.size();
    out_.append(sizeof(T), '\0');
    return at;
  }
  template <typename T>
  void Patch(size_t at, const T& value) {
    std::memcpy(out_.data() + at, &value, sizeof(T));
  }
  size_t size() const { return out_.size(); }
  std::string Take() { return std::move(out_); }

 private:
  std::string out_;
};

class ByteReader {
 public:
  // `name` prefixes every error ("run.ckpt: ...").
  ByteReader(std::string_view data, std::string name) : data_(data), name_(std::move(name)) {}

  template <typename T>
  Status Get(const char* field, T* value) {
    static_assert(std::is_trivially_copyable_v<T>);
    GROVE_RETURN_IF_ERROR(Need(field, sizeof(T)));
    std::memcpy(value, data_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return Status::Ok();
  }
  Status GetBytes(const char* field, void* out, size_t size) {
    GROVE_RETURN_IF_ERROR(Need(field, size));
    if (size == 0) return Status::Ok();  // `out` may be an empty vector's null data()
    std::memcpy(out, data_.data() + pos_, size);
    pos_ += size;
    return Status::Ok();
  }
  Status GetString(const char* field, std::string* s) {
    uint64_t size = 0;
    GROVE_RETURN_IF_ERROR(Get(field, &size));
    GROVE_RETURN_IF_ERROR(Need(field, size));
    s->assign(data_.data() + pos_, size);
    pos_ += size;
    return Status::Ok();
  }
  // A count of records of at least `min_record_bytes` each: refused when the rest of the input
  // cannot hold that many, so no count makes the caller allocate more than the file's size.
  Status GetCount(const char* field, size_t min_record_bytes, uint64_t* count) {
    GROVE_RETURN_IF_ERROR(Get(field, count));
    if (min_record_bytes > 0 && *count > remaining() / min_record_bytes) {
      return Error(field, "count " + std::to_string(*count) + " is larger than the " +
                              std::to_string(remaining()) + " bytes left can hold");
    }
    return Status::Ok();
  }

  size_t offset() const { return pos_; }
  const std::string& name() const { return name_; }
  size_t remaining() const { return data_.size() - pos_; }
  bool at_end() const { return pos_ == data_.size(); }

  // DataLoss: "<name>: byte <offset>: <field>: <what>".
  Status Error(const char* field, const std::string& what) const {
    return DataLossError(name_ + ": byte " + std::to_string(kCheckpointHeaderBytes + pos_) + ": " +
                         field + ": " + what);
  }

 private:
  Status Need(const char* field, uint64_t size) const {
    if (size > remaining()) {
      return Error(field, "needs " + std::to_string(size) + " bytes, " +
                              std::to_string(remaining()) + " left (truncated or corrupt)");
    }
    return Status::Ok();
  }

  std::string_view data_;
  std::string name_;
  size_t pos_ = 0;
};

// The last part of loading a graph of reference-counted nodes (PersistentTrie, PoseHistory):
// reads `root_count` u32 root ids (0: none, k: nodes[k - 1]) into `roots`, counts a reference for
// each, checks that every node is referenced (refs[k] counts the links found so far) and gives
// each node its count (a new node holds one). `accept(k)` says whether node k may be a root.
// On error nothing is changed but `refs`; the caller frees the nodes.
template <typename NodeT, typename Accept>
Status LinkRoots(ByteReader* r, const char* field, size_t root_count,
                 const std::vector<NodeT*>& nodes, std::vector<uint32_t>* refs, Accept&& accept,
                 std::vector<NodeT*>* roots) {
  std::vector<NodeT*> loaded(root_count, nullptr);
  for (size_t i = 0; i < root_count; ++i) {
    uint32_t id = 0;
    GROVE_RETURN_IF_ERROR(r->Get(field, &id));
    if (id == 0) continue;
    if (id > nodes.size() || !accept(id - 1)) {
      return r->Error(field, std::to_string(id) + " is not a node that can start a version");
    }
    loaded[i] = nodes[id - 1];
    ++(*refs)[id - 1];
  }
  for (size_t k = 0; k < nodes.size(); ++k) {
    if ((*refs)[k] == 0) {
      return r->Error(field, "node " + std::to_string(k) + " is reached from nothing");
    }
  }
  for (size_t k = 0; k < nodes.size(); ++k) {
    for (uint32_t j = 1; j < (*refs)[k]; ++j) nodes[k]->rc.Acquire();
  }
  roots->insert(roots->end(), loaded.begin(), loaded.end());
  return Status::Ok();
}

// One configuration field in a checkpoint's field block: integers (and choices) as the bits of
// an int64, reals as the bits of a double.
struct CheckpointField {
  std::string name;
  bool integer;
  uint64_t bits;
  const FieldInfo* info = nullptr;  // the table's row, for messages (choices by name)
};

// The fields of `config` that change results, in table order: the block a checkpoint stores.
template <typename Config>
std::vector<CheckpointField> CheckpointFieldsOf(const std::vector<ConfigField<Config>>& table,
                                                const Config& config) {
  std::vector<CheckpointField> out;
  for (const ConfigField<Config>& f : table) {
    if (f.info.effect != kChangesResults) continue;
    FieldValue v = f.get(config);
    uint64_t bits = 0;
    if (const double* d = std::get_if<double>(&v)) {
      std::memcpy(&bits, d, sizeof(bits));
    } else if (const int64_t* i = std::get_if<int64_t>(&v)) {
      bits = static_cast<uint64_t>(*i);
    } else {
      bits = std::get<uint64_t>(v);
    }
    out.push_back({f.info.name, f.info.type != FieldType::kReal, bits, &f.info});
  }
  return out;
}

// Writes the head of a body: the kind, the configuration hash and block, the user data.
void WriteCheckpointHead(ByteWriter* w, std::string_view kind,
                         const std::vector<CheckpointField>& fields, std::string_view user_data);

// Reads the head of a body made by WriteCheckpointHead() and checks it against this build and
// configuration, before any engine is built: the kind (DataLoss when it is not `kind`), the
// format version (FailedPrecondition unless `version` is `expected_version`), then every field
// (FailedPrecondition naming the field and both values when a value differs; DataLoss when the
// block does not have the expected fields). `model` names the model in messages ("FootSLAM").
// Sets *user_data.
Status ReadCheckpointHead(ByteReader* r, std::string_view kind, const char* model, uint32_t version,
                          uint32_t expected_version, const std::vector<CheckpointField>& expected,
                          std::string* user_data);

// The whole file: header and `body`.
// Reads a model body's particle count: DataLoss naming both counts unless it is `expected`.
Status ReadParticleCount(ByteReader* r, uint64_t expected);

std::string SealCheckpoint(std::string_view body, uint32_t format_version);

struct UnsealedCheckpoint {
  uint32_t format_version;
  std::string_view body;  // a view into the file
};

// Checks the header and the checksum of a whole file and returns its body and format version
// (which the model checks after the kind: ReadCheckpointHead). DataLoss for a short file, a
// wrong magic, a length or checksum that does not match. `name` starts each message.
StatusOr<UnsealedCheckpoint> UnsealCheckpoint(std::string_view file, const std::string& name);

}  // namespace grove

#endif  // GROVE_ENGINE_IO_CHECKPOINT_IO_H_
