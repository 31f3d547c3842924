#include "engine/io/checkpoint_io.h"

#include <fmt/format.h>

#include <limits>

#include "grove/checksum.h"

namespace grove {
namespace {

constexpr char kMagic[8] = {'\x89', 'G', 'R', 'O', 'V', 'E', '\r', '\n'};

template <typename T>
T Load(const char* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

// The block of fields as written; its CRC-32 is the configuration hash.
std::string FieldBlock(const std::vector<CheckpointField>& fields) {
  ByteWriter w;
  w.Put<uint64_t>(fields.size());
  for (const CheckpointField& f : fields) {
    w.PutString(f.name);
    w.Put<uint8_t>(f.integer ? 1 : 0);
    w.Put<uint64_t>(f.bits);
  }
  return w.Take();
}

// A stored value as the configuration writes it (a choice by its name).
std::string FieldText(const CheckpointField& f, uint64_t bits) {
  if (f.integer) {
    if (f.info != nullptr && f.info->type == FieldType::kChoice) {
      return FormatFieldValue(*f.info, FieldValue(static_cast<int64_t>(bits)));
    }
    if (f.info != nullptr && f.info->type == FieldType::kUnsigned) return std::to_string(bits);
    return std::to_string(static_cast<int64_t>(bits));
  }
  double v;
  std::memcpy(&v, &bits, sizeof(v));
  return fmt::format("{}", v);
}

}  // namespace

void WriteCheckpointHead(ByteWriter* w, std::string_view kind,
                         const std::vector<CheckpointField>& fields, std::string_view user_data) {
  w->PutString(kind);
  std::string block = FieldBlock(fields);
  w->Put<uint32_t>(Crc32(block));
  w->PutBytes(block.data(), block.size());
  w->PutString(user_data);
}

Status ReadCheckpointHead(ByteReader* r, std::string_view kind, const char* model, uint32_t version,
                          uint32_t expected_version, const std::vector<CheckpointField>& expected,
                          std::string* user_data) {
  std::string stored_kind;
  GROVE_RETURN_IF_ERROR(r->GetString("kind", &stored_kind));
  if (stored_kind != kind) {
    return r->Error(
        "kind", fmt::format("{} is not a {} checkpoint", QuoteForMessage(stored_kind, 40), model));
  }
  if (version != expected_version) {
    return FailedPreconditionError(
        fmt::format("{}: {} checkpoint format version {} cannot be read by this grove, which "
                    "reads version {}",
                    r->name(), model, version, expected_version));
  }
  uint32_t hash = 0;
  uint64_t count = 0;
  GROVE_RETURN_IF_ERROR(r->Get("configuration hash", &hash));
  GROVE_RETURN_IF_ERROR(r->GetCount("configuration field count", 17, &count));
  if (count != expected.size()) {
    return r->Error("configuration field count",
                    std::to_string(count) + ", expected " + std::to_string(expected.size()));
  }
  for (const CheckpointField& f : expected) {
    std::string name;
    uint8_t integer = 0;
    uint64_t bits = 0;
    GROVE_RETURN_IF_ERROR(r->GetString("configuration field name", &name));
    GROVE_RETURN_IF_ERROR(r->Get("configuration field type", &integer));
    GROVE_RETURN_IF_ERROR(r->Get("configuration field value", &bits));
    if (name != f.name || integer != (f.integer ? 1 : 0)) {
      return r->Error("configuration field name",
                      QuoteForMessage(name, 40) + ", expected \"" + f.name + "\"");
    }
    if (bits != f.bits) {
      return FailedPreconditionError(fmt::format(
          "{}: the checkpoint was made with {} = {}, this configuration has {} = {}: resume with "
          "the configuration of the interrupted run (only threads and batch may change)",
          r->name(), f.name, FieldText(f, bits), f.name, FieldText(f, f.bits)));
    }
  }
  if (hash != Crc32(FieldBlock(expected))) {
    return r->Error("configuration hash", "does not match the fields");
  }
  return r->GetString("user data", user_data);
}

std::string SealCheckpoint(std::string_view body, uint32_t format_version) {
  ByteWriter w;
  w.PutBytes(kMagic, sizeof(kMagic));
  w.Put<uint32_t>(format_version);
  w.Put<uint32_t>(Crc32(body));
  w.Put<uint64_t>(body.size());
  std::string file = w.Take();
  file.append(body);
  return file;
}

StatusOr<UnsealedCheckpoint> UnsealCheckpoint(std::string_view file, const std::string& name) {
  if (file.size() < sizeof(kMagic) || std::memcmp(file.data(), kMagic, sizeof(kMagic)) != 0) {
    return DataLossError(name +
                         ": not a grove checkpoint (the first 8 bytes are not the magic "
                         "\\x89GROVE\\r\\n)");
  }
  if (file.size() < kCheckpointHeaderBytes) {
    return DataLossError(name + ": truncated: " + std::to_string(file.size()) +
                         " bytes, shorter than the " + std::to_string(kCheckpointHeaderBytes) +
                         "-byte header");
  }
  const uint32_t version = Load<uint32_t>(file.data() + 8);
  const uint32_t crc = Load<uint32_t>(file.data() + 12);
  const uint64_t length = Load<uint64_t>(file.data() + 16);
  const uint64_t actual = file.size() - kCheckpointHeaderBytes;
  if (length != actual) {
    return DataLossError(name + ": " + (actual < length ? "truncated" : "trailing bytes") +
                         ": the header says " + std::to_string(length) + " bytes of data, the " +
                         "file holds " + std::to_string(actual));
  }
  std::string_view body = file.substr(kCheckpointHeaderBytes);
  if (Crc32(body) != crc) {
    return DataLossError(name + ": checksum mismatch: the file is corrupt");
  }
  return UnsealedCheckpoint{version, body};
}

Status ReadParticleCount(ByteReader* r, uint64_t expected) {
  uint64_t n = 0;
  GROVE_RETURN_IF_ERROR(r->Get("particle count", &n));
  if (n != expected) {
    return r->Error("particle count", std::to_string(n) + " does not match the configuration's " +
                                          std::to_string(expected));
  }
  return Status::Ok();
}

}  // namespace grove
