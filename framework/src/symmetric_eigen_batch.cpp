// The largest eigenpairs of many symmetric matrices, eight at a time: each
// matrix in one lane of a 512-bit vector, the smaller ones padded with zeros.
// Every step is a vertical operation on eight independent problems (no sum
// across lanes), so a matrix's result does not depend on which matrices
// share its batch, and the latency-bound parts of a single solve (one
// division per step of a Sturm count, one reflector at a time) overlap eight
// ways. Per matrix at n = 100: 60-105 us for 2-9 pairs against 135-246 us
// for largest_eigenpairs (docs/performance.md, "Clustering").
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "prt/error.hpp"
#include "prt/symmetric_eigen.hpp"

namespace prt {

namespace {

constexpr int kLanes = 8;
typedef double Lanes __attribute__((vector_size(8 * kLanes)));

Lanes splat(double x) {
  return Lanes{} + x;
}
Lanes lane_abs(Lanes x) {
  return x < 0 ? -x : x;
}
Lanes lane_max(Lanes a, Lanes b) {
  return a > b ? a : b;
}
Lanes lane_min(Lanes a, Lanes b) {
  return a < b ? a : b;
}
Lanes lane_sqrt(Lanes x) {
  for (int l = 0; l < kLanes; ++l) x[l] = std::sqrt(x[l]);
  return x;
}

constexpr double kEps = std::numeric_limits<double>::epsilon();

// Householder reduction of each lane's lower triangle (column-major n x n in
// `a`) to a tridiagonal (d, e), as LAPACK's dsytd2 'L': reflector k acts on
// rows k + 1.., its vector [1, a(k + 2.., k)] with coefficient tau[k].
void tridiagonalise(Eigen::Index n, std::vector<Lanes>& a, std::vector<Lanes>& d,
                    std::vector<Lanes>& e, std::vector<Lanes>& tau) {
  d.assign(std::size_t(n), splat(0));
  e.assign(std::size_t(n), splat(0));
  tau.assign(std::size_t(n), splat(0));
  std::vector<Lanes> p(static_cast<std::size_t>(n));
  for (Eigen::Index k = 0; k + 2 < n; ++k) {
    Lanes* v = &a[std::size_t(k * n)];  // column k: its rows k + 1.. become the reflector
    const Eigen::Index s = k + 1;
    const Lanes alpha = v[s];
    Lanes below = splat(0);
    for (Eigen::Index i = s + 1; i < n; ++i) below += v[i] * v[i];
    const auto flat = below == 0;  // nothing to annihilate: H = I
    const Lanes norm = lane_sqrt(alpha * alpha + below);
    const Lanes beta = alpha >= 0 ? -norm : norm;
    const Lanes scale = flat ? splat(0) : 1.0 / (flat ? splat(1) : alpha - beta);
    const Lanes t = flat ? splat(0) : (beta - alpha) / (flat ? splat(1) : beta);
    tau[std::size_t(k)] = t;
    e[std::size_t(k)] = flat ? alpha : beta;
    v[s] = splat(1);
    for (Eigen::Index i = s + 1; i < n; ++i) v[i] *= scale;
    // p = t A' v over the trailing lower triangle, four partial sums per
    // column to overlap the multiply-adds' latency.
    for (Eigen::Index i = s; i < n; ++i) p[std::size_t(i)] = splat(0);
    for (Eigen::Index j = s; j < n; ++j) {
      const Lanes* column = &a[std::size_t(j * n)];
      const Lanes vj = v[j];
      Lanes sum0 = column[j] * vj, sum1 = splat(0), sum2 = splat(0), sum3 = splat(0);
      Eigen::Index i = j + 1;
      for (; i + 4 <= n; i += 4) {
        p[std::size_t(i)] += column[i] * vj;
        sum0 += column[i] * v[i];
        p[std::size_t(i + 1)] += column[i + 1] * vj;
        sum1 += column[i + 1] * v[i + 1];
        p[std::size_t(i + 2)] += column[i + 2] * vj;
        sum2 += column[i + 2] * v[i + 2];
        p[std::size_t(i + 3)] += column[i + 3] * vj;
        sum3 += column[i + 3] * v[i + 3];
      }
      // The tail keeps the pattern (entry i to sum (i - j - 1) mod 4), so that
      // zero rows padding a smaller matrix add exact zeros to the same sums.
      for (Lanes* sum : {&sum0, &sum1, &sum2}) {
        if (i >= n) break;
        p[std::size_t(i)] += column[i] * vj;
        *sum += column[i] * v[i];
        ++i;
      }
      p[std::size_t(j)] += (sum0 + sum1) + (sum2 + sum3);
    }
    Lanes pv = splat(0);
    for (Eigen::Index i = s; i < n; ++i) {
      p[std::size_t(i)] *= t;
      pv += p[std::size_t(i)] * v[i];
    }
    const Lanes half = 0.5 * t * pv;
    for (Eigen::Index i = s; i < n; ++i) p[std::size_t(i)] -= half * v[i];
    // A' -= v w^T + w v^T, w = p - (t/2)(p . v) v.
    for (Eigen::Index j = s; j < n; ++j) {
      Lanes* column = &a[std::size_t(j * n)];
      const Lanes vj = v[j], wj = p[std::size_t(j)];
      for (Eigen::Index i = j; i < n; ++i) column[i] -= v[i] * wj + p[std::size_t(i)] * vj;
    }
  }
  for (Eigen::Index k = 0; k < n; ++k) d[std::size_t(k)] = a[std::size_t(k * n + k)];
  if (n >= 2) e[std::size_t(n - 2)] = a[std::size_t((n - 2) * n + n - 1)];
}

// Number of eigenvalues below x[r] in each lane (Sturm count of the pivots of
// T - x I), for kShifts shifts at once: their divisions overlap.
constexpr int kShifts = 4;
void sturm_counts(Eigen::Index n, const std::vector<Lanes>& d, const std::vector<Lanes>& e2,
                  Lanes pivmin, const Lanes* x, Lanes* count) {
  Lanes q[kShifts];
  for (int r = 0; r < kShifts; ++r) {
    q[r] = d[0] - x[r];
    q[r] = lane_abs(q[r]) <= pivmin ? -pivmin : q[r];
    count[r] = q[r] < 0 ? splat(1) : splat(0);
  }
  for (Eigen::Index i = 1; i < n; ++i)
    for (int r = 0; r < kShifts; ++r) {
      Lanes t = (d[std::size_t(i)] - x[r]) - e2[std::size_t(i - 1)] / q[r];
      t = lane_abs(t) <= pivmin ? -pivmin : t;
      count[r] += t < 0 ? splat(1) : splat(0);
      q[r] = t;
    }
}

// The `count` largest eigenvalues of each lane's tridiagonal, descending, by
// bisection to an absolute width of a few ulps of the matrix's norm (as
// dstebz). A lane stops when its own interval is narrow enough.
std::vector<Lanes> largest_eigenvalues(Eigen::Index n, const std::vector<Lanes>& d,
                                       const std::vector<Lanes>& e, int count, Lanes sizes,
                                       Lanes& norm) {
  std::vector<Lanes> e2(static_cast<std::size_t>(n));
  Lanes low = splat(std::numeric_limits<double>::infinity()), high = -low, largest_e2 = splat(0);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Lanes left = i > 0 ? lane_abs(e[std::size_t(i - 1)]) : splat(0);
    const Lanes right = i + 1 < n ? lane_abs(e[std::size_t(i)]) : splat(0);
    low = lane_min(low, d[std::size_t(i)] - left - right);
    high = lane_max(high, d[std::size_t(i)] + left + right);
    e2[std::size_t(i)] = e[std::size_t(i)] * e[std::size_t(i)];
    largest_e2 = lane_max(largest_e2, e2[std::size_t(i)]);
  }
  // The interval holds 0 too, so that zero rows padding a matrix leave it as
  // it is (and with it every bisection step above 0).
  low = lane_min(low, splat(0));
  high = lane_max(high, splat(0));
  norm = lane_max(lane_abs(low), lane_abs(high));
  const Lanes pivmin = std::numeric_limits<double>::min() * lane_max(splat(1), largest_e2);
  const Lanes fudge = 2.0 * sizes * kEps * norm + 4.0 * pivmin;  // each lane's own size
  low -= fudge;
  high += fudge;
  const Lanes tolerance = 2.0 * kEps * norm + 4.0 * pivmin;
  std::vector<Lanes> values(static_cast<std::size_t>(count));
  for (int first = 0; first < count; first += kShifts) {
    Lanes lo[kShifts], hi[kShifts], x[kShifts], below[kShifts];
    double index[kShifts];  // ascending index of the wanted eigenvalue
    for (int r = 0; r < kShifts; ++r) {
      lo[r] = low;
      hi[r] = high;
      index[r] = double(n - 1 - std::min(first + r, count - 1));
    }
    for (int step = 0; step < 128; ++step) {
      bool active = false;
      for (int r = 0; r < kShifts; ++r) {
        x[r] = 0.5 * (lo[r] + hi[r]);
        for (int l = 0; l < kLanes; ++l) active |= hi[r][l] - lo[r][l] > tolerance[l];
      }
      if (!active) break;
      sturm_counts(n, d, e2, pivmin, x, below);
      for (int r = 0; r < kShifts; ++r) {
        const auto open = hi[r] - lo[r] > tolerance;
        const auto up = below[r] <= index[r];  // the wanted eigenvalue is above x
        lo[r] = open && up ? x[r] : lo[r];
        hi[r] = open && !up ? x[r] : hi[r];
      }
    }
    for (int r = 0; r < kShifts && first + r < count; ++r)
      values[std::size_t(first + r)] = 0.5 * (lo[r] + hi[r]);
  }
  return values;
}

// A fixed start for inverse iteration, the same in every lane: entries in
// [-1, 1) from a small congruential sequence.
double start_entry(Eigen::Index i, int pair) {
  std::uint64_t s =
      std::uint64_t(i) * 6364136223846793005ULL + std::uint64_t(pair + 1) * 1442695040888963407ULL;
  s ^= s >> 33;
  s *= 0xff51afd7ed558ccdULL;
  s ^= s >> 33;
  return double(s >> 11) * (2.0 / 9007199254740992.0) - 1.0;
}

// Solves (T - shift I) z = b in place in each lane, by Gaussian elimination
// with partial pivoting of the tridiagonal (LAPACK dgttrf/dgttrs); pivots
// below `tiny` are replaced by it, as dlagts perturbs them, so that inverse
// iteration at an exact eigenvalue still grows towards its vector.
void shifted_solve(Eigen::Index n, const std::vector<Lanes>& d, const std::vector<Lanes>& e,
                   Lanes shift, Lanes tiny, std::vector<Lanes>& z) {
  thread_local std::vector<Lanes> u0, u1, u2, multiplier,
      swapped;  // swapped: 1 where rows i, i + 1 swap
  for (auto* v : {&u0, &u1, &u2, &multiplier, &swapped}) v->assign(std::size_t(n), splat(0));
  for (Eigen::Index i = 0; i < n; ++i) u0[std::size_t(i)] = d[std::size_t(i)] - shift;
  for (Eigen::Index i = 0; i + 1 < n; ++i) u1[std::size_t(i)] = e[std::size_t(i)];
  for (Eigen::Index i = 0; i + 1 < n; ++i) {
    const std::size_t k = std::size_t(i);
    const Lanes sub = e[k];
    const auto swap = lane_abs(sub) > lane_abs(u0[k]);
    // Without a swap: row i + 1 -= (sub / u0) row i.
    const Lanes pivot = swap ? sub : u0[k];
    const Lanes safe = lane_abs(pivot) < tiny ? (pivot < 0 ? -tiny : tiny) : pivot;
    const Lanes other = swap ? u0[k] : sub;  // the entry eliminated
    const Lanes factor = other / safe;
    const Lanes next_diag = u0[k + 1], next_super = i + 2 < n ? u1[k + 1] : splat(0);
    // Row i after a swap: (sub, u0[k+1], u1[k+1]); row i + 1: (u0[k], u1[k], 0).
    const Lanes row_i1 = swap ? next_diag : u1[k];
    const Lanes row_i2 = swap ? next_super : splat(0);
    const Lanes row_j1 = swap ? u1[k] : next_diag;
    const Lanes row_j2 = swap ? splat(0) : next_super;
    u0[k] = safe;
    u1[k] = row_i1;
    u2[k] = row_i2;
    u0[k + 1] = row_j1 - factor * row_i1;
    if (i + 2 < n) u1[k + 1] = row_j2 - factor * row_i2;
    multiplier[k] = factor;
    swapped[k] = swap ? splat(1) : splat(0);
  }
  {
    const std::size_t k = std::size_t(n - 1);
    u0[k] = lane_abs(u0[k]) < tiny ? (u0[k] < 0 ? -tiny : tiny) : u0[k];
  }
  // Forward: apply the swaps and multipliers to z.
  for (Eigen::Index i = 0; i + 1 < n; ++i) {
    const std::size_t k = std::size_t(i);
    const auto swap = swapped[k] != 0;
    const Lanes top = swap ? z[k + 1] : z[k], bottom = swap ? z[k] : z[k + 1];
    z[k] = top;
    z[k + 1] = bottom - multiplier[k] * top;
  }
  // Back substitution with the upper factor (three diagonals).
  for (Eigen::Index i = n - 1; i >= 0; --i) {
    const std::size_t k = std::size_t(i);
    Lanes r = z[k];
    if (i + 1 < n) r -= u1[k] * z[k + 1];
    if (i + 2 < n) r -= u2[k] * z[k + 2];
    z[k] = r / u0[k];
  }
}

Lanes dot(const std::vector<Lanes>& a, const std::vector<Lanes>& b) {
  Lanes s = splat(0);
  for (std::size_t i = 0; i < a.size(); ++i) s += a[i] * b[i];
  return s;
}

void normalise(std::vector<Lanes>& z) {
  const Lanes norm = lane_sqrt(dot(z, z));
  const Lanes inverse = norm > 0 ? 1.0 / (norm > 0 ? norm : splat(1)) : splat(0);
  for (Lanes& v : z) v *= inverse;
}

// The eigenvectors of each lane's tridiagonal for `values` (descending), by
// inverse iteration (as dstein): shifts of eigenvalues closer than
// 10 eps |value| moved apart, and each vector made orthogonal to those of
// eigenvalues within 1e-3 of the norm.
std::vector<std::vector<Lanes>> tridiagonal_vectors(Eigen::Index n, const std::vector<Lanes>& d,
                                                    const std::vector<Lanes>& e,
                                                    const std::vector<Lanes>& values, Lanes norm,
                                                    Lanes sizes) {
  const int count = int(values.size());
  const Lanes tiny = kEps * lane_max(norm, splat(std::numeric_limits<double>::min()));
  const Lanes close = 1e-3 * norm;
  std::vector<std::vector<Lanes>> vectors(static_cast<std::size_t>(count));
  std::vector<Lanes> shifts(static_cast<std::size_t>(count));
  for (int j = 0; j < count; ++j) {
    Lanes shift = values[std::size_t(j)];
    if (j > 0) {
      const Lanes apart = 10.0 * kEps * lane_abs(shift);
      const Lanes previous = shifts[std::size_t(j - 1)];
      shift = shift >= previous - apart ? previous - apart : shift;
    }
    shifts[std::size_t(j)] = shift;
    std::vector<Lanes>& z = vectors[std::size_t(j)];
    z.resize(std::size_t(n));
    // Zero on the padding: there the solves then keep exact zeros.
    for (Eigen::Index i = 0; i < n; ++i)
      z[std::size_t(i)] = double(i) < sizes ? splat(start_entry(i, j)) : splat(0);
    normalise(z);
    for (int iteration = 0; iteration < 3; ++iteration) {
      shifted_solve(n, d, e, shift, tiny, z);
      normalise(z);
      for (int k = 0; k < j; ++k) {
        const auto near = lane_abs(values[std::size_t(k)] - values[std::size_t(j)]) <= close;
        const Lanes overlap = near ? dot(z, vectors[std::size_t(k)]) : splat(0);
        for (Eigen::Index i = 0; i < n; ++i)
          z[std::size_t(i)] -= overlap * vectors[std::size_t(k)][std::size_t(i)];
      }
      normalise(z);
    }
  }
  return vectors;
}

// z <- Q z, Q = H_0 ... H_{n-3} the tridiagonalisation's reflectors.
void back_transform(Eigen::Index n, const std::vector<Lanes>& a, const std::vector<Lanes>& tau,
                    std::vector<Lanes>& z) {
  for (Eigen::Index k = n - 3; k >= 0; --k) {
    const Lanes t = tau[std::size_t(k)];
    const Lanes* v = &a[std::size_t(k * n)];
    Lanes s = z[std::size_t(k + 1)];
    for (Eigen::Index i = k + 2; i < n; ++i) s += v[i] * z[std::size_t(i)];
    s *= t;
    z[std::size_t(k + 1)] -= s;
    for (Eigen::Index i = k + 2; i < n; ++i) z[std::size_t(i)] -= s * v[i];
  }
}

// A v = lambda v and V^T V = I within `tolerance` of the matrix's largest
// entry: else the single solver decides.
bool accurate(const Eigen::MatrixXd& a, const Eigenpairs& pairs, double scale) {
  const double tolerance = 64.0 * double(a.rows()) * kEps;
  if (!pairs.values.allFinite() || !pairs.vectors.allFinite()) return false;
  const Eigen::MatrixXd residual = a * pairs.vectors - pairs.vectors * pairs.values.asDiagonal();
  if (residual.cwiseAbs().maxCoeff() > tolerance * scale) return false;
  const Eigen::MatrixXd gram = pairs.vectors.transpose() * pairs.vectors;
  return (gram - Eigen::MatrixXd::Identity(gram.rows(), gram.cols())).cwiseAbs().maxCoeff() <=
         tolerance;
}

// Up to kLanes matrices of sizes 3..n, each finite with a nonzero largest
// entry `scales[m]`, the smaller ones padded with zero rows and columns to n.
void solve_batch(const std::vector<const Eigen::MatrixXd*>& batch,
                 const std::vector<double>& scales, Eigen::Index count,
                 const std::vector<Eigenpairs*>& out) {
  Eigen::Index n = 0;
  for (const Eigen::MatrixXd* m : batch) n = std::max(n, m->rows());
  // Kept per thread: a fresh 8 n^2 doubles (640 KB at n = 100) per batch
  // cost more in page faults than the reduction itself. Only the lower
  // triangle is written and read.
  thread_local std::vector<Lanes> a;
  a.resize(std::size_t(n * n));
  Lanes sizes = splat(0);
  for (int l = 0; l < kLanes; ++l) {
    // Unused lanes repeat the first matrix: their results are dropped.
    const std::size_t m = std::size_t(l) < batch.size() ? std::size_t(l) : 0;
    const Eigen::MatrixXd& matrix = *batch[m];
    const Eigen::Index size = matrix.rows();
    sizes[l] = double(size);
    const double inverse = 1.0 / scales[m];
    for (Eigen::Index c = 0; c < n; ++c)
      for (Eigen::Index r = c; r < n; ++r)
        a[std::size_t(c * n + r)][l] = r < size ? matrix(r, c) * inverse : 0.0;
  }
  std::vector<Lanes> d, e, tau;
  tridiagonalise(n, a, d, e, tau);
  Lanes norm;
  const std::vector<Lanes> values = largest_eigenvalues(n, d, e, int(count), sizes, norm);
  std::vector<std::vector<Lanes>> vectors = tridiagonal_vectors(n, d, e, values, norm, sizes);
  for (auto& z : vectors) back_transform(n, a, tau, z);
  for (std::size_t m = 0; m < batch.size(); ++m) {
    const Eigen::Index size = batch[m]->rows();
    Eigenpairs pairs;
    pairs.values.resize(count);
    pairs.vectors.resize(size, count);
    for (Eigen::Index j = 0; j < count; ++j) {
      pairs.values[j] = values[std::size_t(j)][m] * scales[m];
      for (Eigen::Index i = 0; i < size; ++i)
        pairs.vectors(i, j) = vectors[std::size_t(j)][std::size_t(i)][m];
    }
    *out[m] = accurate(*batch[m], pairs, scales[m]) ? std::move(pairs)
                                                    : largest_eigenpairs(*batch[m], count);
  }
}

}  // namespace

std::vector<Eigenpairs> largest_eigenpairs_batch(
    const std::vector<const Eigen::MatrixXd*>& matrices, Eigen::Index count) {
  std::vector<Eigenpairs> out(matrices.size());
  // The batched ones, by size: a batch pads to its largest.
  struct Item {
    std::size_t index;
    Eigen::Index size;
    double scale;
  };
  std::vector<Item> items;
  for (std::size_t i = 0; i < matrices.size(); ++i) {
    const Eigen::MatrixXd& a = *matrices[i];
    if (a.rows() != a.cols())
      throw Error("largest_eigenpairs_batch: matrix " + std::to_string(i) + " is not square");
    const Eigen::Index n = a.rows();
    const double scale = a.allFinite() ? a.cwiseAbs().maxCoeff() : 0.0;
    // Small, large, zero or non-finite matrices, and counts beyond the size:
    // the single solver's answers. Over kLargestBatchedEigen, eight matrices
    // no longer fit in L2 (8 n^2 doubles) and the batch gains little.
    if (n <= 2 || n > kLargestBatchedEigen || count <= 0 || count > n || !(scale > 0) ||
        !std::isfinite(scale)) {
      out[i] = largest_eigenpairs(a, count);
      continue;
    }
    items.push_back({i, n, scale});
  }
  std::stable_sort(items.begin(), items.end(),
                   [](const Item& a, const Item& b) { return a.size < b.size; });
  std::vector<const Eigen::MatrixXd*> batch;
  std::vector<double> scales;
  std::vector<Eigenpairs*> targets;
  for (std::size_t first = 0; first < items.size(); first += kLanes) {
    batch.clear(), scales.clear(), targets.clear();
    for (std::size_t i = first; i < std::min(items.size(), first + kLanes); ++i) {
      batch.push_back(matrices[items[i].index]);
      scales.push_back(items[i].scale);
      targets.push_back(&out[items[i].index]);
    }
    solve_batch(batch, scales, count, targets);
  }
  return out;
}

}  // namespace prt
