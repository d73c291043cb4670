#include "prt/sh_rotation.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <string>

#include "prt/error.hpp"

namespace prt::sh {
namespace {

constexpr double kSqrt2 = 1.41421356237309504880;

// R = Rz(alpha) Ry(beta) Rz(gamma), in the forms the recursion and the assembly need. For
// beta > pi/2 the recursion runs at pi - beta (flip), using H^{m',m}(beta) = (-1)^{l+m+m'}
// H^{-m',m}(pi - beta): the Legendre seeds are computed from 1 - cos, which is only accurate
// near cos = 1 (without the flip, |B B^T - I| reaches 6e-11 at l = 500 for pi - beta = 1e-3).
struct Euler {
  double cos_beta, sin_beta, one_minus_cos, one_plus_cos;  // of the recursion angle
  double cos_alpha, sin_alpha, cos_gamma, sin_gamma;
  bool flip;
};

// For the unit quaternion (w, x, y, z) of Rz(a) Ry(b) Rz(g):
//   w + i z = cos(b/2) e^{i (a + g)/2},  y - i x = sin(b/2) e^{i (a - g)/2}.
// Whichever of the two is large has an exact phase; the phase of the small one only enters
// multiplied by powers of its modulus, so nothing is divided by a small sin(beta) and the
// degenerate cases beta = 0, pi need no special branch. 1 -+ cos(beta) come out exact too.
Euler euler_from(const Eigen::Matrix3d& rotation) {
  if (!rotation.allFinite()) throw Error("sh::Rotation: the rotation matrix is not finite");
  Eigen::Quaterniond q(rotation);
  q.normalize();  // absorbs a slightly non-orthonormal input
  const double ra = std::sqrt(q.w() * q.w() + q.z() * q.z());  // |q| = 1: no overflow
  const double rb = std::sqrt(q.y() * q.y() + q.x() * q.x());
  Euler e;
  e.flip = rb > ra;
  const double c = e.flip ? rb : ra, s = e.flip ? ra : rb;  // cos, sin of the recursion angle / 2
  e.cos_beta = (c - s) * (c + s);
  e.sin_beta = 2.0 * c * s;
  e.one_minus_cos = 2.0 * s * s;
  e.one_plus_cos = 2.0 * c * c;
  double ac = 1.0, as = 0.0, bc = 1.0, bs = 0.0;  // e^{i (a + g)/2}, e^{i (a - g)/2}
  if (ra > 0.0) ac = q.w() / ra, as = q.z() / ra;
  if (rb > 0.0) bc = q.y() / rb, bs = -q.x() / rb;
  e.cos_alpha = ac * bc - as * bs;
  e.sin_alpha = as * bc + ac * bs;
  e.cos_gamma = ac * bc + as * bs;
  e.sin_gamma = as * bc - ac * bs;
  return e;
}

// sqrt(i) and 1 / sqrt(i) (0 for i = 0), i < count, so that per-band constants are products.
void fill_roots(std::size_t count, double* root, double* inv_root) {
  for (std::size_t i = 0; i < count; ++i) {
    root[i] = std::sqrt(double(i));
    inv_root[i] = i ? 1.0 / root[i] : 0.0;
  }
}

// Per-band constants, kFields arrays of n + 2 values for band n:
//  e[j] = sqrt((n - j)(n + j + 1)) / 2 and 1 / e[j] (the d^j_n of the m' recursion);
//  t1..t3[m]: the three weights of H^{1,m}_n in terms of H^{0,*}_{n+1} (G&D eq. 41).
// root / inv_root must reach index 2n + 2.
enum Field { kE, kInvE, kT1, kT2, kT3, kFields };

std::size_t table_size(int n) {
  return std::size_t(kFields) * (n + 2);
}

void fill_band_table(int n, const double* root, const double* inv_root, double* table) {
  const int s = n + 2;
  std::fill(table, table + table_size(n), 0.0);
  double *e = table + kE * s, *inv_e = table + kInvE * s;
  double *t1 = table + kT1 * s, *t2 = table + kT2 * s, *t3 = table + kT3 * s;
  for (int j = 0; j <= n; ++j) e[j] = 0.5 * root[n - j] * root[n + j + 1];
  for (int j = 0; j < n; ++j) inv_e[j] = 2.0 * inv_root[n - j] * inv_root[n + j + 1];
  const double inv = inv_root[n] * inv_root[n + 1];
  for (int m = 1; m <= n; ++m) {
    t1[m] = -0.5 * root[n + m + 1] * root[n + m + 2] * inv;
    t2[m] = -0.5 * root[n - m + 1] * root[n - m + 2] * inv;
    t3[m] = -root[n + m + 1] * root[n - m + 1] * inv;
  }
}

// Low bands (the common, speed-critical case) read their constants from tables built once
// (thread-safe static initialisation); higher bands recompute theirs, O(n) products next to the
// O(n^2) band itself.
constexpr int kCachedBands = 64;
constexpr std::size_t kCachedRoots = 2 * kCachedBands + 4;

std::size_t table_offset(int n) {
  return std::size_t(kFields) * (std::size_t(n) * (n + 3) / 2);
}

struct Cache {
  std::vector<double> root, inv_root, tables;
  Cache() : root(kCachedRoots), inv_root(kCachedRoots), tables(table_offset(kCachedBands)) {
    fill_roots(kCachedRoots, root.data(), inv_root.data());
    for (int n = 0; n < kCachedBands; ++n)
      fill_band_table(n, root.data(), inv_root.data(), tables.data() + table_offset(n));
  }
};

const Cache& cache() {
  static const Cache instance;
  return instance;
}

// Schmidt semi-normalised P~_d^m(cos beta) = sqrt((d-m)!/(d+m)!) P_d^m (no Condon-Shortley
// phase; P~_n^m = H^{0,m}_n) for d = n + 1, m = 0..d, from degree n. The usual degree recurrence
// P~_d = a x P~_{d-1} - b P~_{d-2} needs x = cos(beta) itself, whose rounding near x = 1 costs
// ~ d^2 ulp (1e-11 at d = 500); instead it runs on D_d = P~_d - g_d P~_{d-1}, g_d = sqrt((d+m) /
// (d-m)) being the ratio at x = 1, with u = 1 - x (exact, and <= 1 thanks to the flip):
//   D_d = (d-1-m) / sqrt(d^2 - m^2) D_{d-1} - a u P~_{d-1},  P~_d = g_d P~_{d-1} + D_d.
// Values below the double range are negligible for degrees up to ~1800 (the sectoral seeds
// that matter there are >= e^{-d/e}).
void legendre_next(int n, const double* root, const double* inv_root, const Euler& e,
                   const double* p, const double* dp, double* p_next, double* dp_next) {
  const int d = n + 1;  // degree produced
  const double u = e.one_minus_cos;
  for (int m = 0; m < n; ++m) {
    const double inv = inv_root[d - m] * inv_root[d + m];
    dp_next[m] = (d - 1 - m) * inv * dp[m] - (2 * d - 1) * inv * u * p[m];
    p_next[m] = root[d + m] * inv_root[d - m] * p[m] + dp_next[m];
  }
  const double g = root[2 * d - 1];  // m = n: g = a = sqrt(2d - 1), no D_{d-1} term
  dp_next[n] = -g * u * p[n];
  p_next[n] = g * p[n] + dp_next[n];
  p_next[d] = dp_next[d] = g * inv_root[2 * d] * e.sin_beta * p[n];  // sectoral
}

// sign^k cos(k angle), sign^k sin(k angle), k = 0..top, by complex multiplication (error ~ k
// ulp). The sign lets the assembly fold (-1)^m into the gamma tables.
void fill_trig(int top, double c1, double s1, double sign, double* c, double* s) {
  double cr = 1.0, sr = 0.0, f = 1.0;
  c[0] = 1.0, s[0] = 0.0;
  for (int k = 1; k <= top; ++k) {
    const double next = cr * c1 - sr * s1;
    sr = sr * c1 + cr * s1;
    cr = next;
    f *= sign;
    c[k] = f * cr, s[k] = f * sr;
  }
}

// cos/sin(k alpha) and (-1)^m cos/sin(m gamma) (without the (-1)^m under the flip).
struct Trig {
  const double *cos_alpha, *sin_alpha, *cos_gamma, *sin_gamma;
};

std::size_t wedge_size(int n) {
  return std::size_t(2 * n + 1) * (n + 2);
}

// One row of G&D eq. 50 solved for |m'| + 1 (the same form for m' > 0 and m' < 0):
//   H^{+-(p+1),m} = (e[p-1] H^{+-(p-1),m} - e[m-1] H^{+-p,m-1} + e[m] H^{+-p,m+1}) / e[p],
// m = first..n, from rows a = +-(p-1) and b = +-p; column n + 1 stays zero.
void recur_row(int first, int n, double ep, double ip, const double* __restrict e,
               const double* __restrict a, const double* __restrict b, double* __restrict c) {
  for (int m = first; m <= n; ++m) c[m] = ip * (ep * a[m] - e[m - 1] * b[m - 1] + e[m] * b[m + 1]);
  c[n + 1] = 0.0;
}

// The 2x2 group on rows (k, -k) and columns (m, -m); plus, minus point at entries (k, 0), (-k, 0).
inline void put_group(int m, double A, double B, double ck, double sk, double cg, double sg,
                      double* plus, double* minus) {
  const double cc = ck * cg, ss = sk * sg, sc = sk * cg, cs = ck * sg;
  const double cos_p = cc - ss, cos_m = cc + ss, sin_p = sc + cs, sin_m = sc - cs;
  plus[m] = A * cos_p + B * cos_m;
  plus[-m] = B * sin_m - A * sin_p;
  minus[m] = A * sin_p + B * sin_m;
  minus[-m] = A * cos_p - B * cos_m;
}

// put_group for m = first..last with A = ha[m], B = hb[m]: contiguous and spelt out, so that
// it vectorises.
void put_groups(int first, int last, const double* __restrict ha, const double* __restrict hb,
                double ck, double sk, const double* __restrict cg, const double* __restrict sg,
                double* __restrict plus, double* __restrict minus) {
  for (int m = first; m <= last; ++m) {
    const double A = ha[m], B = hb[m];
    const double cc = ck * cg[m], ss = sk * sg[m], sc = sk * cg[m], cs = ck * sg[m];
    const double cos_p = cc - ss, cos_m = cc + ss, sin_p = sc + cs, sin_m = sc - cs;
    plus[m] = A * cos_p + B * cos_m;
    plus[-m] = B * sin_m - A * sin_p;
    minus[m] = A * sin_p + B * sin_m;
    minus[-m] = A * cos_p - B * cos_m;
  }
}

// Real block of band n >= 1, row-major into `out`. p0, p1: P~_n, P~_{n+1} of cos(beta). `wedge`
// (wedge_size(n) doubles) receives H^{m',m}_n for m' = -n..n, |m'| <= m <= n, with a zero column
// m = n + 1 so the recursion needs no end case; the symmetries H^{m',m} = H^{m,m'} =
// H^{-m',-m} give the rest.
void band_block(int n, const double* table, const Euler& eu, const double* p0, const double* p1,
                const Trig& trig, double* wedge, double* out) {
  const int s = n + 2;
  const double *e = table + kE * s, *inv_e = table + kInvE * s;
  const double *t1 = table + kT1 * s, *t2 = table + kT2 * s, *t3 = table + kT3 * s;
  auto row = [&](int mp) { return wedge + std::ptrdiff_t(mp + n) * s; };

  double* h0 = row(0);  // H^{0,m}_n = P~_n^m
  for (int m = 0; m <= n; ++m) h0[m] = p0[m];
  h0[n + 1] = 0.0;
  double* h1 = row(1);  // H^{1,m}_n from H^{0,*}_{n+1} (G&D eq. 41)
  for (int m = 1; m <= n; ++m)
    h1[m] = t1[m] * eu.one_minus_cos * p1[m + 1] + t2[m] * eu.one_plus_cos * p1[m - 1] +
            t3[m] * eu.sin_beta * p1[m];
  h1[n + 1] = 0.0;
  double* hm1 = row(-1);  // m' = -1: G&D eq. 50 at m' = 0, where d^0_n = +e[0]
  for (int m = 1; m <= n; ++m)
    hm1[m] = -h1[m] + inv_e[0] * (e[m] * h0[m + 1] - e[m - 1] * h0[m - 1]);
  hm1[n + 1] = 0.0;
  for (int sign : {1, -1})
    for (int p = 1; p < n; ++p)
      recur_row(p + 1, n, e[p - 1], inv_e[p], e, row(sign * (p - 1)), row(sign * p),
                row(sign * (p + 1)));

  // Real block = Z(alpha) Y(beta) Z(gamma). For k, m > 0, with A = (-1)^m H^{k,m},
  // B = (-1)^m H^{k,-m}, the 2x2 group on rows (k, -k) and columns (m, -m) is
  //   [ A cos(ka + mg) + B cos(ka - mg),  -A sin(ka + mg) + B sin(ka - mg) ]
  //   [ A sin(ka + mg) + B sin(ka - mg),   A cos(ka + mg) - B cos(ka - mg) ];
  // row and column 0 are the same with A = B, scaled by 1/sqrt(2) each. (-1)^m sits in the
  // gamma tables. With the flip (H at pi - beta), A = (-1)^{n+k} H^{k,-m} and
  // B = (-1)^{n+k} H^{k,m}: the sign goes on the alpha terms and A, B swap sources.
  const int w = 2 * n + 1;
  double* center = out + std::size_t(n) * w + n;  // entry (0, 0)
  const double *ca = trig.cos_alpha, *sa = trig.sin_alpha;
  const double *cg = trig.cos_gamma, *sg = trig.sin_gamma;
  const bool flip = eu.flip;
  const double band_sign = flip && (n & 1) ? -1.0 : 1.0;
  center[0] = band_sign * h0[0];
  for (int m = 1; m <= n; ++m) {
    const double a = band_sign * kSqrt2 * h0[m];
    const double b = (flip && (m & 1) ? -a : a);
    center[m] = a * cg[m];
    center[-m] = -a * sg[m];
    center[m * w] = b * ca[m];
    center[-m * w] = b * sa[m];
  }
  // H^{k,m} = H^{m,k} and H^{k,-m} = H^{-k,m} = H^{-m,k}: for m >= k read rows +-k, for m < k
  // column k of rows +-m. In tiles, so that those columns stay in cache at high degree.
  const int a_side = flip ? -1 : 1;  // the wedge side A is read from
  constexpr int kTile = 32;
  for (int k0 = 1; k0 <= n; k0 += kTile) {
    const int k1 = std::min(n, k0 + kTile - 1);
    for (int m0 = 1; m0 <= n; m0 += kTile) {
      const int m1 = std::min(n, m0 + kTile - 1);
      for (int k = k0; k <= k1; ++k) {
        double *plus = center + k * w, *minus = center - k * w;  // rows k and -k
        const double row_sign = flip && (k & 1) ? -band_sign : band_sign;
        const double ck = row_sign * ca[k], sk = row_sign * sa[k];
        int m = m0;
        for (const int end = std::min(m1, k - 1); m <= end; ++m)
          put_group(m, row(a_side * m)[k], row(-a_side * m)[k], ck, sk, cg[m], sg[m], plus, minus);
        put_groups(m, m1, row(a_side * k), row(-a_side * k), ck, sk, cg, sg, plus, minus);
      }
    }
  }
}

// Scratch memory: thread-local for small sizes, so the common low-order rotation allocates
// nothing after a thread's first call; a plain vector for high orders, so it is returned.
class Scratch {
 public:
  explicit Scratch(std::size_t size) {
    constexpr std::size_t kThreadLocalMax = std::size_t(1) << 16;
    if (size <= kThreadLocalMax) {
      thread_local std::vector<double> local;
      if (local.size() < size) local.resize(size);
      data_ = local.data();
    } else {
      own_.resize(size);
      data_ = own_.data();
    }
  }
  double* take(std::size_t n) {
    double* p = data_ + used_;
    used_ += n;
    return p;
  }

 private:
  std::vector<double> own_;
  double* data_ = nullptr;
  std::size_t used_ = 0;
};

// Everything needed to produce bands 1..top in increasing order.
class BandBuilder {
 public:
  BandBuilder(int top, const Eigen::Matrix3d& rotation)
      : euler_(euler_from(rotation)), scratch_(scratch_size(top)) {
    p_ = scratch_.take(top + 3);
    dp_ = scratch_.take(top + 3);
    p_next_ = scratch_.take(top + 3);
    dp_next_ = scratch_.take(top + 3);
    double* t = scratch_.take(4 * std::size_t(top + 1));
    fill_trig(top, euler_.cos_alpha, euler_.sin_alpha, 1.0, t, t + (top + 1));
    fill_trig(top, euler_.cos_gamma, euler_.sin_gamma, euler_.flip ? 1.0 : -1.0, t + 2 * (top + 1),
              t + 3 * (top + 1));
    trig_ = {t, t + (top + 1), t + 2 * (top + 1), t + 3 * (top + 1)};
    wedge_ = scratch_.take(wedge_size(top));
    const Cache& c = cache();
    if (root_count(top) <= kCachedRoots) {
      root_ = c.root.data(), inv_root_ = c.inv_root.data();
    } else {
      double* r = scratch_.take(2 * root_count(top));
      fill_roots(root_count(top), r, r + root_count(top));
      root_ = r, inv_root_ = r + root_count(top);
    }
    table_ = top >= kCachedBands ? scratch_.take(table_size(top)) : nullptr;
    p_[0] = dp_[0] = 1.0;  // P~_0
    legendre_next(0, root_, inv_root_, euler_, p_, dp_, p_next_, dp_next_);
  }

  // Band n into `out` (row-major); n >= 1, never below the previous call's band.
  void build(int n, double* out) {
    while (band_ < n) {  // Legendre rows to degrees (n, n + 1)
      ++band_;
      std::swap(p_, p_next_);
      std::swap(dp_, dp_next_);
      legendre_next(band_, root_, inv_root_, euler_, p_, dp_, p_next_, dp_next_);
    }
    const double* table = table_;
    if (n < kCachedBands)
      table = cache().tables.data() + table_offset(n);
    else
      fill_band_table(n, root_, inv_root_, table_);
    band_block(n, table, euler_, p_, p_next_, trig_, wedge_, out);
  }

 private:
  static std::size_t root_count(int top) { return 2 * std::size_t(top) + 4; }
  static std::size_t scratch_size(int top) {
    const std::size_t roots = root_count(top) <= kCachedRoots ? 0 : 2 * root_count(top);
    const std::size_t table = top >= kCachedBands ? table_size(top) : 0;
    return 4 * std::size_t(top + 3) + 4 * std::size_t(top + 1) + wedge_size(top) + roots + table;
  }

  int band_ = 0;
  Euler euler_;
  Scratch scratch_;
  double *p_, *dp_, *p_next_, *dp_next_;  // P~ and D of degrees n, n + 1
  double *wedge_, *table_;
  const double *root_, *inv_root_;
  Trig trig_;
};

// y = B x for a row-major w x w block: four independent partial sums per row, so the dot
// products pipeline (and vectorise) without reassociation flags.
inline void block_times(const double* b, int w, const double* x, double* y) {
  const int w4 = w & ~3;
  for (int i = 0; i < w; ++i, b += w) {
    double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
    for (int j = 0; j < w4; j += 4) {
      s0 += b[j] * x[j];
      s1 += b[j + 1] * x[j + 1];
      s2 += b[j + 2] * x[j + 2];
      s3 += b[j + 3] * x[j + 3];
    }
    for (int j = w4; j < w; ++j) s0 += b[j] * x[j];
    y[i] = (s0 + s1) + (s2 + s3);
  }
}

}  // namespace

Rotation::Rotation(int order, const Eigen::Matrix3d& rotation) : order_(std::max(order, 0)) {
  if (order_ == 0) return;
  blocks_.resize(band_offset(order_));
  blocks_[0] = 1.0;
  if (order_ == 1) return;
  BandBuilder builder(order_ - 1, rotation);
  for (int l = 1; l < order_; ++l) builder.build(l, blocks_.data() + band_offset(l));
}

Rotation::Block Rotation::band(int l) const {
  if (l < 0 || l >= order_)
    throw Error("sh::Rotation::band: band " + std::to_string(l) + " outside 0.." +
                std::to_string(order_ - 1));
  return Block(blocks_.data() + band_offset(l), 2 * l + 1, 2 * l + 1);
}

void Rotation::apply(const Eigen::Ref<const Eigen::MatrixXd>& in,
                     Eigen::Ref<Eigen::MatrixXd> out) const {
  const Eigen::Index n = Eigen::Index(order_) * order_;
  if (in.rows() != n || out.rows() != n || in.cols() != out.cols())
    throw Error("sh::Rotation::apply: expected " + std::to_string(n) + " x k matrices, got " +
                std::to_string(in.rows()) + " x " + std::to_string(in.cols()) + " and " +
                std::to_string(out.rows()) + " x " + std::to_string(out.cols()));
  for (Eigen::Index c = 0; c < in.cols(); ++c) {
    const double* x = in.data() + c * in.outerStride();
    double* y = out.data() + c * out.outerStride();
    for (int l = 0; l < order_; ++l)
      block_times(blocks_.data() + band_offset(l), 2 * l + 1, x + l * l, y + l * l);
  }
}

Eigen::MatrixXd Rotation::dense() const {
  const Eigen::Index n = Eigen::Index(order_) * order_;
  Eigen::MatrixXd result = Eigen::MatrixXd::Zero(n, n);
  for (int l = 0; l < order_; ++l) result.block(l * l, l * l, 2 * l + 1, 2 * l + 1) = band(l);
  return result;
}

void rotation_band(int l, const Eigen::Matrix3d& rotation, double* out) {
  if (l < 0) throw Error("sh::rotation_band: negative band " + std::to_string(l));
  if (l == 0) {
    out[0] = 1.0;
    return;
  }
  BandBuilder builder(l, rotation);
  builder.build(l, out);
}

}  // namespace prt::sh
