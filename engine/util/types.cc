#include "grove/types.h"

#include <fmt/format.h>

namespace grove {

std::string FilterSummary::BriefFilterReport(std::string_view model) const {
  const double total = filter_s();
  const double rate = total > 0 ? static_cast<double>(particles) * steps / total : 0;
  return fmt::format(
      "{}: {} particles x {} steps on {} thread(s) in {:.2f} s ({:.2f} M particle-steps/s, {:.0f} "
      "ns per particle-step); {} resamplings, mean ESS {:.0f} ({:.1f} %); phases: advance {:.2f} "
      "s, normalise {:.2f} s, resample {:.2f} s, release {:.2f} s, bookkeeping {:.2f} s",
      model, particles, steps, threads_used, total, rate / 1e6, rate > 0 ? 1e9 / rate : 0.0,
      resamplings, mean_ess, particles > 0 ? 100.0 * mean_ess / particles : 0.0, advance_s,
      normalize_s, resample_s, release_s, bookkeeping_s);
}

}  // namespace grove
