#include "grove/checksum.h"

#include <zlib.h>

#include <algorithm>
#include <limits>

namespace grove {

uint32_t Crc32(std::string_view data, uint32_t crc) {
  uLong c = crc;
  // zlib takes lengths as uInt: feed large inputs in pieces.
  while (!data.empty()) {
    const size_t piece = std::min<size_t>(data.size(), std::numeric_limits<uInt>::max());
    c = crc32(c, reinterpret_cast<const Bytef*>(data.data()), static_cast<uInt>(piece));
    data.remove_prefix(piece);
  }
  return static_cast<uint32_t>(c);
}

}  // namespace grove
