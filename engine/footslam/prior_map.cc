#include "engine/footslam/prior_map.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace grove::footslam {

Status BuildPriorMap(const std::vector<HexCounts>& map, double confidence,
                     const std::function<bool(Hex, uint64_t*)>& key_of, PriorMap* prior,
                     int64_t* outside) {
  for (size_t k = 0; k < map.size(); ++k) {
    const HexCounts& h = map[k];
    PriorHex p{};
    for (int e = 0; e < 6; ++e) {
      if (!std::isfinite(h.counts[e]) || h.counts[e] < 0) {
        return InvalidArgumentError(
            fmt::format("prior map row {} (q = {}, r = {}): c{} = {}: counts must be finite "
                        "and >= 0",
                        k, h.q, h.r, e, h.counts[e]));
      }
      p.edge[e] = confidence * h.counts[e];
      p.total += p.edge[e];
    }
    if (!std::isfinite(p.total)) {
      return InvalidArgumentError(fmt::format(
          "prior map row {} (q = {}, r = {}): the counts times prior_map_confidence = {} "
          "overflow",
          k, h.q, h.r, confidence));
    }
    uint64_t key;
    if (!key_of(Hex{h.q, h.r}, &key)) {
      ++*outside;
      continue;
    }
    if (!prior->Insert(key, p)) {
      return InvalidArgumentError(
          fmt::format("prior map row {}: hexagon (q = {}, r = {}) is given twice", k, h.q, h.r));
    }
  }
  return Status::Ok();
}

std::vector<std::pair<uint64_t, const PriorHex*>> SortedHexes(const PriorMap& map) {
  std::vector<std::pair<uint64_t, const PriorHex*>> hexes;
  map.ForEach([&](uint64_t key, const PriorHex& p) { hexes.push_back({key, &p}); });
  std::sort(hexes.begin(), hexes.end());
  return hexes;
}

void SavePriorMap(const PriorMap& map, ByteWriter* w) {
  std::vector<std::pair<uint64_t, const PriorHex*>> hexes = SortedHexes(map);
  w->Put<uint64_t>(hexes.size());
  for (const auto& [key, p] : hexes) {
    w->Put(key);
    w->PutBytes(p->edge, sizeof(p->edge));
  }
}

Status LoadPriorMap(ByteReader* r, const char* what, uint64_t key_count, PriorMap* map) {
  const std::string name(what);
  uint64_t count = 0;
  GROVE_RETURN_IF_ERROR(
      r->GetCount((name + " hexagon count").c_str(), 7 * sizeof(uint64_t), &count));
  uint64_t last = 0;
  for (uint64_t k = 0; k < count; ++k) {
    uint64_t key = 0;
    PriorHex p{};
    GROVE_RETURN_IF_ERROR(r->Get((name + " hexagon key").c_str(), &key));
    if (key >= key_count || (k > 0 && key <= last)) {
      return r->Error((name + " hexagon key").c_str(),
                      "outside the grid or not in increasing order");
    }
    last = key;
    GROVE_RETURN_IF_ERROR(
        r->GetBytes((name + " hexagon counters").c_str(), p.edge, sizeof(p.edge)));
    for (double c : p.edge) {
      if (!std::isfinite(c) || c < 0)
        return r->Error((name + " hexagon counters").c_str(), "impossible value");
    }
    p.total = EdgeSum(p);
    if (!std::isfinite(p.total))
      return r->Error((name + " hexagon counters").c_str(), "impossible value");
    map->Insert(key, p);
  }
  return Status::Ok();
}

}  // namespace grove::footslam
