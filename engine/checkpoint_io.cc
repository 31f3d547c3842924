#include "engine/checkpoint_io.h"

#include <zlib.h>

#include <limits>

namespace grove {
namespace {

constexpr char kMagic[8] = {'\x89', 'G', 'R', 'O', 'V', 'E', '\r', '\n'};

uint32_t Crc32(std::string_view data) {
  uLong crc = crc32(0L, Z_NULL, 0);
  // zlib takes lengths as uInt: feed large bodies in pieces.
  while (!data.empty()) {
    size_t piece = std::min<size_t>(data.size(), std::numeric_limits<uInt>::max());
    crc = crc32(crc, reinterpret_cast<const Bytef*>(data.data()), static_cast<uInt>(piece));
    data.remove_prefix(piece);
  }
  return static_cast<uint32_t>(crc);
}

template <typename T>
T Load(const char* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

}  // namespace

std::string SealCheckpoint(std::string_view body) {
  ByteWriter w;
  w.PutBytes(kMagic, sizeof(kMagic));
  w.Put<uint32_t>(kCheckpointFormatVersion);
  w.Put<uint32_t>(Crc32(body));
  w.Put<uint64_t>(body.size());
  std::string file = w.Take();
  file.append(body);
  return file;
}

StatusOr<std::string_view> UnsealCheckpoint(std::string_view file, const std::string& name) {
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
  if (version != kCheckpointFormatVersion) {
    return FailedPreconditionError(name + ": checkpoint format version " + std::to_string(version) +
                                   " cannot be read by this grove, which reads version " +
                                   std::to_string(kCheckpointFormatVersion));
  }
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
  return body;
}

}  // namespace grove
