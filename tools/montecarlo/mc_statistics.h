// Statistics of Monte Carlo runs (`grove fastslam montecarlo`): means, variances, Student-t
// confidence intervals over runs, the chi-square acceptance interval of the average NEES, and the
// pose NEES itself. Quantiles come from Boost.Math (header-only; not in this header).
//
// Thread safety: all functions are thread-safe (no shared state).
#ifndef GROVE_TOOLS_MONTECARLO_MC_STATISTICS_H_
#define GROVE_TOOLS_MONTECARLO_MC_STATISTICS_H_

#include <cstdint>
#include <span>

#include "grove/types.h"

namespace grove::tools {

// The arithmetic mean; NaN for no values.
double Mean(std::span<const double> values);
// The variance about the mean with divisor n (of a whole series, e.g. a run's squared errors
// over time); NaN for no values.
double PopulationVariance(std::span<const double> values);
// The unbiased sample variance, divisor n - 1 (of a sample, e.g. one figure over runs); NaN for
// fewer than 2 values.
double SampleVariance(std::span<const double> values);

// The p-quantile of Student's t with `dof` degrees of freedom, and of chi-square with `dof`
// degrees of freedom. NaN when p is not in (0, 1) or dof is not > 0 and finite.
double StudentTQuantile(double p, double dof);
double ChiSquareQuantile(double p, double dof);

struct ConfidenceInterval {
  double mean = 0;
  double low = 0;   // mean - half_width
  double high = 0;  // mean + half_width
  double half_width = 0;
  int64_t count = 0;
};

// The two-sided `level` confidence interval of the mean of `values`, taken as a sample of
// independent runs: mean +- t_{(1 + level) / 2, n - 1} * s / sqrt(n), s^2 the sample variance.
// With fewer than 2 values (or a level outside (0, 1)) the mean is kept and the bounds and the
// half width are NaN; with no values everything is NaN.
ConfidenceInterval StudentTInterval(std::span<const double> values, double level = 0.95);

struct NeesInterval {
  double low = 0;
  double high = 0;
};

// The two-sided `level` acceptance interval of the average NEES of `runs` independent runs of a
// consistent filter whose error has `dof` dimensions: N times the average is chi-square with
// dof * N degrees of freedom, so the interval is [chi2_{(1 - level) / 2}(dof N) / N,
// chi2_{(1 + level) / 2}(dof N) / N] (Bar-Shalom, Li and Kirubarajan, Estimation with
// Applications to Tracking and Navigation, 5.4.2). For dof = 3, N = 30: [2.19, 3.94] (the seed
// paper's Section 4.3 gives 2.19 and 3.93). NaN bounds for dof < 1 or runs < 1.
NeesInterval AverageNeesInterval(int dof, int64_t runs, double level = 0.95);

// `angle` wrapped to [-pi, pi].
double WrapAngle(double angle);

// The normalised estimation error squared d^T P^-1 d of a pose error d = (dx, dy, dheading)
// (heading wrapped by the caller) under the covariance P. NaN when P is not positive definite
// up to round-off: a Cholesky pivot (the variance of a component given the ones before it) that
// is not finite or not above 1e-9 times the component's variance (all particles alike, or
// fewer than 4 distinct poses), or when an input is not finite.
double PoseNees(double dx, double dy, double dheading, const Pose2Covariance& p);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_MONTECARLO_MC_STATISTICS_H_
