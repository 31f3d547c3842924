#include "tools/montecarlo/mc_statistics.h"

#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/students_t.hpp>
#include <cmath>
#include <exception>
#include <limits>
#include <numbers>

namespace grove::tools {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

bool UsableQuantileArguments(double p, double dof) {
  return p > 0 && p < 1 && dof > 0 && std::isfinite(dof);
}

}  // namespace

double Mean(std::span<const double> values) {
  if (values.empty()) return kNaN;
  double sum = 0;
  for (double v : values) sum += v;
  return sum / static_cast<double>(values.size());
}

double PopulationVariance(std::span<const double> values) {
  if (values.empty()) return kNaN;
  const double mean = Mean(values);
  double sum = 0;
  for (double v : values) sum += (v - mean) * (v - mean);
  return sum / static_cast<double>(values.size());
}

double SampleVariance(std::span<const double> values) {
  if (values.size() < 2) return kNaN;
  const double mean = Mean(values);
  double sum = 0;
  for (double v : values) sum += (v - mean) * (v - mean);
  return sum / static_cast<double>(values.size() - 1);
}

double StudentTQuantile(double p, double dof) {
  if (!UsableQuantileArguments(p, dof)) return kNaN;
  try {
    return boost::math::quantile(boost::math::students_t_distribution<double>(dof), p);
  } catch (const std::exception&) {  // Boost's default policy throws on overflow
    return kNaN;
  }
}

double ChiSquareQuantile(double p, double dof) {
  if (!UsableQuantileArguments(p, dof)) return kNaN;
  try {
    return boost::math::quantile(boost::math::chi_squared_distribution<double>(dof), p);
  } catch (const std::exception&) {
    return kNaN;
  }
}

ConfidenceInterval StudentTInterval(std::span<const double> values, double level) {
  ConfidenceInterval ci;
  ci.count = static_cast<int64_t>(values.size());
  ci.mean = Mean(values);
  const double n = static_cast<double>(values.size());
  const double t = StudentTQuantile(0.5 * (1 + level), n - 1);  // NaN for n < 2
  ci.half_width = t * std::sqrt(SampleVariance(values) / n);
  ci.low = ci.mean - ci.half_width;
  ci.high = ci.mean + ci.half_width;
  return ci;
}

NeesInterval AverageNeesInterval(int dof, int64_t runs, double level) {
  if (dof < 1 || runs < 1) return {kNaN, kNaN};
  const double n = static_cast<double>(runs);
  const double total_dof = static_cast<double>(dof) * n;
  return {ChiSquareQuantile(0.5 * (1 - level), total_dof) / n,
          ChiSquareQuantile(0.5 * (1 + level), total_dof) / n};
}

double WrapAngle(double angle) { return std::remainder(angle, 2 * std::numbers::pi); }

double PoseNees(double dx, double dy, double dheading, const Pose2Covariance& p) {
  // Cholesky factor L of P (row by row), then d^T P^-1 d = |L^-1 d|^2.
  const double a[3][3] = {{p.xx, p.xy, p.xh}, {p.xy, p.yy, p.yh}, {p.xh, p.yh, p.hh}};
  const double d[3] = {dx, dy, dheading};
  for (double v : d) {
    if (!std::isfinite(v)) return kNaN;
  }
  double l[3][3] = {};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j <= i; ++j) {
      double s = a[i][j];
      for (int k = 0; k < j; ++k) s -= l[i][k] * l[j][k];
      if (i == j) {
        // Not above a tiny fraction of the diagonal: singular up to round-off.
        if (!std::isfinite(s) || !(s > 1e-9 * a[i][i])) return kNaN;
        l[i][i] = std::sqrt(s);
      } else {
        l[i][j] = s / l[j][j];
      }
    }
  }
  double nees = 0;
  double y[3];
  for (int i = 0; i < 3; ++i) {
    double s = d[i];
    for (int k = 0; k < i; ++k) s -= l[i][k] * y[k];
    y[i] = s / l[i][i];
    nees += y[i] * y[i];
  }
  return std::isfinite(nees) ? nees : kNaN;
}

}  // namespace grove::tools
