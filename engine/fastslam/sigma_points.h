// Sigma-point transforms for the landmark filters of the seed's family: the scaled
// unscented transform of U-FastSLAM and the central-difference (Stirling) transform of the
// square-root central difference Kalman filter (SR-CDKF), with the factorisations they need.
//
// Sources: Julier, "The scaled unscented transformation" (ACC 2002) and van der Merwe's thesis,
// "Sigma-Point Kalman Filters for Probabilistic Inference in Dynamic State-Space Models" (OGI,
// 2004), ch. 3 (UT weights, CDKF weights, SR-CDKF, Algorithm 11); Nørgaard, Poulsen, Ravn, "New
// developments in state estimation for nonlinear systems" (Automatica 2000) for h = sqrt(3).
//
// Scaled unscented transform of x ~ N(m, A A^T), x of dimension L:
//   lambda = alpha^2 (L + kappa) - L + offset, points m and m +- sqrt(L + lambda) A_k,
//   wm0 = lambda / (L + lambda), wc0 = wm0 + 1 - alpha^2 + beta, wm_k = wc_k = 1 / (2 (L +
//   lambda)). (Kim's U-FastSLAM code adds the dimension of the noise it leaves out of the
//   augmentation to lambda: `offset`.)
// Central-difference transform (Stirling interpolation, half-step h; h^2 = 3 is optimal for a
// Gaussian): points m and m +- h A_k,
//   wm0 = (h^2 - L) / h^2, wm_k = 1 / (2 h^2), wc1 = 1 / (4 h^2), wc2 = (h^2 - 1) / (4 h^4),
//   Y mean = sum wm Y, and the square-root covariance of y is the triangular factor of the QR of
//   [sqrt(wc1) (Y_k - Y_{L+k}), sqrt(wc2) (Y_k + Y_{L+k} - 2 Y_0)]_{k=1..L} (and the columns of
//   an additive noise's root), never formed as a covariance. Its cross-covariance with x is
//   A (sqrt(wc1) (Y_k - Y_{L+k}))^T.
//   (The seed's Eq. 14 lost its exponents in the extraction: "h2-L / h", "1/2h", "1/4h2",
//   "h2-1/4h2" are read as above, van der Merwe's Eq. 3.98-3.100.)
//
// Angles: a component of y marked as an angle is unwrapped to within pi of the central point's
// before any sum, so points on either side of +-pi average correctly; the mean may then lie
// outside (-pi, pi] (callers wrap innovations).
//
// Factors are lower triangular with a non-negative diagonal ("Cholesky factors"): QR results are
// sign-corrected. Rank-one updates and downdates are Eigen's (llt_inplace::rankUpdate, the code
// behind LLT::rankUpdate); a downdate that would leave the matrix not positive definite is
// reported (FailedPrecondition) and leaves the factor unchanged.
//
// Thread safety: free functions on values; all may be called concurrently.
#ifndef GROVE_ENGINE_FASTSLAM_SIGMA_POINTS_H_
#define GROVE_ENGINE_FASTSLAM_SIGMA_POINTS_H_

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/QR>
#include <cmath>
#include <numbers>

#include "grove/status.h"

namespace grove::fastslam {

template <int R, int C>
using Mat = Eigen::Matrix<double, R, C>;
template <int N>
using Vec = Eigen::Matrix<double, N, 1>;

struct UnscentedWeights {
  double spread = 0;  // sqrt(L + lambda)
  double wm0 = 0, wc0 = 0, wi = 0;
};

// REQUIRES: dimension >= 1, alpha > 0 and L + lambda > 0 (checked by the configuration).
inline UnscentedWeights UnscentedWeightsFor(int dimension, double alpha, double beta, double kappa,
                                            double lambda_offset = 0) {
  const double l = dimension;
  const double lambda = alpha * alpha * (l + kappa) - l + lambda_offset;
  UnscentedWeights w;
  w.spread = std::sqrt(l + lambda);
  w.wm0 = lambda / (l + lambda);
  w.wc0 = w.wm0 + 1 - alpha * alpha + beta;
  w.wi = 1 / (2 * (l + lambda));
  return w;
}

struct CentralDifferenceWeights {
  double h = 0;
  double wm0 = 0, wi = 0;
  double sqrt_wc1 = 0, sqrt_wc2 = 0;
};

// REQUIRES: h >= 1 (wc2 >= 0).
inline CentralDifferenceWeights CentralDifferenceWeightsFor(int dimension, double h) {
  const double h2 = h * h;
  CentralDifferenceWeights w;
  w.h = h;
  w.wm0 = (h2 - dimension) / h2;
  w.wi = 1 / (2 * h2);
  w.sqrt_wc1 = std::sqrt(1 / (4 * h2));
  w.sqrt_wc2 = std::sqrt((h2 - 1) / (4 * h2 * h2));
  return w;
}

// `a` moved by whole turns to within pi of `reference`.
inline double UnwrapNear(double a, double reference) {
  constexpr double kTwoPi = 2 * std::numbers::pi;
  const double d = a - reference;
  if (d > -std::numbers::pi && d <= std::numbers::pi) return a;
  return reference + std::remainder(d, kTwoPi);
}

// For a compound matrix B (M x K), the lower-triangular factor S (M x M, non-negative diagonal)
// with S S^T = B B^T, from the Householder QR of B^T (K x M, K >= M): B^T = Q R, S = R^T with
// each column's sign flipped to make the diagonal non-negative.
template <int M, int K>
Mat<M, M> TriangularFactor(const Mat<M, K>& b) {
  static_assert(K >= M, "the compound matrix needs at least as many columns as rows");
  const Eigen::HouseholderQR<Mat<K, M>> qr(b.transpose());
  Mat<M, M> s = qr.matrixQR().template topRows<M>().template triangularView<Eigen::Upper>();
  s.transposeInPlace();
  for (int j = 0; j < M; ++j) {
    if (s(j, j) < 0) s.col(j) = -s.col(j);
  }
  return s;
}

// L L^T + sigma v v^T in place (sigma = +1: update, -1: downdate), by Eigen's rank-one update of
// a Cholesky factor. FailedPrecondition, `l` unchanged, when the result would not be positive
// definite (a downdate removing more than the matrix holds, or a zero pivot).
template <int N>
Status CholeskyRankOne(Mat<N, N>* l, const Vec<N>& v, double sigma) {
  Mat<N, N> work = *l;
  const Eigen::Index failed =
      Eigen::internal::llt_inplace<double, Eigen::Lower>::rankUpdate(work, v, sigma);
  if (failed >= 0 || !work.allFinite()) {
    return FailedPreconditionError(
        sigma < 0 ? "a Cholesky downdate would leave the covariance not positive definite"
                  : "a Cholesky update did not give a finite factor");
  }
  *l = work.template triangularView<Eigen::Lower>();
  return Status::Ok();
}

// The images under f of the 2L + 1 points mean (into *y0) and mean +- spread * root.col(k)
// (into ys->col(k) and ys->col(L + k)), with output component `angle` (-1: none) unwrapped to
// within pi of y0's. False when f fails at a point.
template <int L, int M, typename F>
bool TransformPoints(const Vec<L>& mean, const Mat<L, L>& root, double spread, int angle, F& f,
                     Vec<M>* y0, Mat<M, 2 * L>* ys) {
  if (!f(mean, y0)) return false;
  for (int k = 0; k < L; ++k) {
    const Vec<L> step = spread * root.col(k);
    Vec<M> y;
    if (!f(Vec<L>(mean + step), &y)) return false;
    ys->col(k) = y;
    if (!f(Vec<L>(mean - step), &y)) return false;
    ys->col(L + k) = y;
  }
  if (angle >= 0) {
    for (int k = 0; k < 2 * L; ++k) (*ys)(angle, k) = UnwrapNear((*ys)(angle, k), (*y0)(angle));
  }
  return true;
}

// y = f(x) for x ~ N(mean, root root^T) by the scaled unscented transform. f(x, &y) -> bool
// (false: x cannot be evaluated, and the transform returns false). Component `angle` of y (-1
// for none) is an angle. Outputs: the mean of y, its covariance and the cross-covariance
// E[(x - mean)(y - y_mean)^T].
template <int L, int M, typename F>
bool UnscentedTransform(const Vec<L>& mean, const Mat<L, L>& root, const UnscentedWeights& w,
                        int angle, F&& f, Vec<M>* y_mean, Mat<M, M>* y_cov, Mat<L, M>* cross) {
  Vec<M> y0;
  Mat<M, 2 * L> ys;
  if (!TransformPoints<L, M>(mean, root, w.spread, angle, f, &y0, &ys)) return false;
  const Vec<M> m = w.wm0 * y0 + w.wi * ys.rowwise().sum();
  const Vec<M> d0 = y0 - m;
  Mat<M, M> cov = w.wc0 * d0 * d0.transpose();
  Mat<L, M> xy = Mat<L, M>::Zero();
  for (int k = 0; k < L; ++k) {
    const Vec<L> step = w.spread * root.col(k);
    const Vec<M> dp = ys.col(k) - m, dm = ys.col(L + k) - m;
    cov += w.wi * (dp * dp.transpose() + dm * dm.transpose());
    xy += w.wi * step * (dp - dm).transpose();
  }
  *y_mean = m;
  *y_cov = 0.5 * (cov + cov.transpose());
  if (cross != nullptr) *cross = xy;
  return true;
}

// y = f(x) for x ~ N(mean, factor factor^T) by the central-difference transform, with an
// additive noise of factor `noise_root` (M x M, may be null). Outputs: the mean of y, the lower
// triangular factor of its covariance, and the scaled first-order differences
// D = [sqrt(wc1) (Y_k - Y_{L+k})]_k (M x L), so that the cross-covariance is factor * D^T.
template <int L, int M, typename F>
bool CentralDifferenceTransform(const Vec<L>& mean, const Mat<L, L>& factor,
                                const CentralDifferenceWeights& w, int angle, F&& f,
                                const Mat<M, M>* noise_root, Vec<M>* y_mean, Mat<M, M>* y_factor,
                                Mat<M, L>* first_order) {
  Vec<M> y0;
  Mat<M, 2 * L> ys;
  if (!TransformPoints<L, M>(mean, factor, w.h, angle, f, &y0, &ys)) return false;
  constexpr int kCols = 2 * L + M;
  Mat<M, kCols> compound = Mat<M, kCols>::Zero();
  for (int k = 0; k < L; ++k) {
    compound.col(k) = w.sqrt_wc1 * (ys.col(k) - ys.col(L + k));
    compound.col(L + k) = w.sqrt_wc2 * (ys.col(k) + ys.col(L + k) - 2 * y0);
  }
  if (noise_root != nullptr) compound.template rightCols<M>() = *noise_root;
  *y_mean = w.wm0 * y0 + w.wi * ys.rowwise().sum();
  *y_factor = TriangularFactor<M, kCols>(compound);
  if (first_order != nullptr) *first_order = compound.template leftCols<L>();
  return true;
}

// log N(v; 0, S S^T) for a lower-triangular factor S with a positive diagonal, and optionally
// the squared Mahalanobis distance. REQUIRES: S's diagonal > 0.
template <int M>
double LogDensityOfFactor(const Mat<M, M>& s, const Vec<M>& v, double* mahalanobis_sq = nullptr) {
  const Vec<M> u = s.template triangularView<Eigen::Lower>().solve(v);
  const double m2 = u.squaredNorm();
  if (mahalanobis_sq != nullptr) *mahalanobis_sq = m2;
  return -0.5 * m2 - 0.5 * M * std::log(2 * std::numbers::pi) - s.diagonal().array().log().sum();
}

// The square-root Kalman update (van der Merwe's Algorithm 11): with the cross-covariance
// p_xz (N x M), the innovation factor s_z (M x M, lower) and the innovation v,
//   K = p_xz (s_z s_z^T)^-1,  x += K v,  S_x <- downdates of S_x by each column of U = K s_z,
// and *log_likelihood = log N(v; 0, s_z s_z^T) (may be null). FailedPrecondition, nothing
// written, when s_z is singular, a downdate would lose positive definiteness or a result is not
// finite.
template <int N, int M>
Status SquareRootUpdate(const Mat<N, M>& p_xz, const Mat<M, M>& s_z, const Vec<M>& v, Vec<N>* x,
                        Mat<N, N>* s_x, double* log_likelihood) {
  if (!(s_z.diagonal().array() > 0).all() || !s_z.allFinite()) {
    return FailedPreconditionError("the innovation covariance is singular");
  }
  // K = p_xz S_z^-T S_z^-1: solve S_z S_z^T K^T = p_xz^T.
  const auto tri = s_z.template triangularView<Eigen::Lower>();
  Mat<M, N> kt = tri.solve(p_xz.transpose());
  kt = tri.transpose().solve(kt);
  const Mat<N, M> k = kt.transpose();
  const Mat<N, M> u = k * s_z;
  Mat<N, N> s = *s_x;
  for (int j = 0; j < M; ++j) GROVE_RETURN_IF_ERROR(CholeskyRankOne<N>(&s, u.col(j), -1));
  const Vec<N> nx = *x + k * v;
  const double ll = LogDensityOfFactor<M>(s_z, v);
  if (!nx.allFinite() || !std::isfinite(ll)) {
    return FailedPreconditionError("the square-root update is not finite");
  }
  *x = nx;
  *s_x = s;
  if (log_likelihood != nullptr) *log_likelihood = ll;
  return Status::Ok();
}

}  // namespace grove::fastslam

#endif  // GROVE_ENGINE_FASTSLAM_SIGMA_POINTS_H_
