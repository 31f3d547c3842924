// CRC-32 (zlib's polynomial), the checksum of checkpoints, input digests and output manifests.
#ifndef GROVE_CHECKSUM_H_
#define GROVE_CHECKSUM_H_

#include <cstdint>
#include <string_view>

#include "grove/export.h"

namespace grove {

// The CRC-32 of `data` continuing from `crc` (0 to start): Crc32(b, Crc32(a)) == Crc32(a + b).
GROVE_EXPORT uint32_t Crc32(std::string_view data, uint32_t crc = 0);

}  // namespace grove

#endif  // GROVE_CHECKSUM_H_
