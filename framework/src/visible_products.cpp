#include "prt/visible_products.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <string>
#include <utility>

#include "prt/error.hpp"
#include "prt/row_blocks.hpp"
#include "prt/transport.hpp"

namespace prt {

PaddedRows::PaddedRows(Eigen::Index rows, Eigen::Index cols)
    : rows_(rows),
      cols_(cols),
      stride_((cols + 7) / 8 * 8),
      data_(static_cast<std::size_t>(rows * stride_), 0.0) {}

PaddedRows::PaddedRows(const Eigen::MatrixXd& matrix) {
  assign(matrix);
}

void PaddedRows::resize(Eigen::Index rows, Eigen::Index cols) {
  rows_ = rows;
  cols_ = cols;
  stride_ = (cols + 7) / 8 * 8;
  // Whole rows of zeros: the padding columns must stay zero.
  data_.assign(static_cast<std::size_t>(rows * stride_), 0.0);
}

PaddedRows::ConstBlock PaddedRows::block(Eigen::Index first, Eigen::Index count) const {
  return ConstBlock(row(first), count, cols_, Eigen::OuterStride<>(stride_));
}

namespace {

// 64 x 64 bits: bit c of a[r] becomes bit r of a[c]. Swaps ever smaller
// off-diagonal blocks (32, 16, ..., 1) in place: 6 x 32 steps, no bit loop.
void transpose_64x64(std::uint64_t a[64]) {
  std::uint64_t mask = 0x00000000FFFFFFFFull;
  for (int width = 32; width != 0; width >>= 1, mask ^= mask << width)
    for (int r = 0; r < 64; r = (r + width + 1) & ~width) {
      const std::uint64_t t = ((a[r] >> width) ^ a[r + width]) & mask;
      a[r + width] ^= t;
      a[r] ^= t << width;
    }
}

}  // namespace

TransposedVisibility::TransposedVisibility(const VisibilityBits& visibility)
    : vertices_(visibility.vertices()),
      directions_(visibility.directions()),
      words_per_direction_(VisibilityBits::words_for(vertices_)),
      bits_(directions_ * words_per_direction_, 0) {
  const std::size_t vertex_words = VisibilityBits::words_for(directions_);
  // A task takes up to 8 words of directions (a cache line or two of each
  // vertex's bits) and walks the vertices in squares of 64, writing each of
  // its rows in order.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vertex_words, 8), [&](const auto& range) {
    std::uint64_t square[64];
    for (std::size_t column = 0; column < words_per_direction_; ++column)
      for (std::size_t w = range.begin(); w < range.end(); ++w) {
        for (std::size_t i = 0; i < 64; ++i) {
          const std::size_t vertex = 64 * column + i;
          square[i] = vertex < vertices_ ? visibility.words(vertex)[w] : 0;
        }
        transpose_64x64(square);
        for (std::size_t i = 0; i < 64 && 64 * w + i < directions_; ++i)
          bits_[(64 * w + i) * words_per_direction_ + column] = square[i];
      }
  });
}

namespace {

// Eight doubles (one AVX-512 register; the compiler splits it on narrower
// machines), moved from and to rows of doubles with unaligned loads and
// stores (memcpy: an attribute on a typedef is lost in templates).
typedef double Packet __attribute__((vector_size(64)));
inline Packet load(const double* from) {
  Packet value;
  std::memcpy(&value, from, sizeof value);
  return value;
}
inline void store(double* to, const Packet& value) {
  std::memcpy(to, &value, sizeof value);
}
constexpr int kMaxPanel = 16;  // packets summed in registers at once (128 columns)

// Both products are one kernel: output row r sums (a_r . b_j) rows.row(j)
// over the set bits j of its bit row, with a the vertices' normals / pi and
// b the directions (T X), or the other way round over the transposed bits
// (T^T Y). Bits are visited a word (64 gathered rows) at a time, a tile that
// stays in L1 (32 KB at 64 columns) while every output row of a call reads
// it. Measured for the bunny at 6,144 directions and 58 columns, one pass on
// two cores: 0.31 s with 512-row tiles (in L2), 0.21 s with 64, 0.25 s with
// 32 (the sums' loads and stores per tile then count).
struct MaskedSums {
  const std::uint64_t* bits;  // bit rows, `words` words each
  std::size_t words;
  // x, y, z per output row and per gathered row: the normals / pi, built
  // per call, and the set's directions, already rows of x, y, z.
  const double* a;
  const double* b;
  const PaddedRows* rows;
};

// a . b of 3 doubles, its multiply-adds fixed: the compiler contracts a plain
// sum of products differently from one kernel to the next, and the rows of
// a pair must get the bits of a row alone.
inline double dot3(const double* a, const double* b) {
  return std::fma(a[2], b[2], std::fma(a[1], b[1], a[0] * b[0]));
}

// out_row += sum over the set bits of `tile` (gathered rows 64 word + bit)
// of (a . b_j) rows.row(j), for one panel of packets. The sum stays in
// registers and adds rows in increasing order, so tiles change no bit of it.
template <int Packets>
struct TileKernel {
  static void run(int first_packet, const MaskedSums& m, const double* a, std::uint64_t tile,
                  std::size_t word, double* out_row) {
    double* target = out_row + 8 * first_packet;
    Packet sum[Packets];
    for (int p = 0; p < Packets; ++p) sum[p] = load(target + 8 * p);
    // Only rows with a set bit are read: bits past the last row are never set.
    const auto stride = static_cast<std::size_t>(m.rows->stride());
    const double* base = m.rows->row(0) + 64 * word * stride + 8 * first_packet;
    const double* b = m.b + 3 * 64 * word;
    for (; tile; tile &= tile - 1) {
      const auto j = static_cast<std::size_t>(std::countr_zero(tile));
      const double c = dot3(a, b + 3 * j);
      const double* row = base + j * stride;
      for (int p = 0; p < Packets; ++p) sum[p] += c * load(row + 8 * p);
    }
    for (int p = 0; p < Packets; ++p) store(target + 8 * p, sum[p]);
  }
};

// The same for two output rows at once: each gathered row of the union of
// their tiles is read once and added to the sum of each row whose bit is set,
// in increasing order as above (the same bits as two single-row calls).
// Neighbouring rows share most bits, and reading the gathered rows from L2 is
// what bounds the single-row kernel.
template <int Packets>
struct TilePairKernel {
  static void run(int first_packet, const MaskedSums& m, const double* a0, const double* a1,
                  std::uint64_t tile0, std::uint64_t tile1, std::size_t word, double* out0,
                  double* out1) {
    double* target0 = out0 + 8 * first_packet;
    double* target1 = out1 + 8 * first_packet;
    Packet sum0[Packets], sum1[Packets];
    for (int p = 0; p < Packets; ++p) sum0[p] = load(target0 + 8 * p);
    for (int p = 0; p < Packets; ++p) sum1[p] = load(target1 + 8 * p);
    const auto stride = static_cast<std::size_t>(m.rows->stride());
    const double* base = m.rows->row(0) + 64 * word * stride + 8 * first_packet;
    const double* b = m.b + 3 * 64 * word;
    for (std::uint64_t both = tile0 | tile1; both; both &= both - 1) {
      const std::uint64_t bit = both & (~both + 1);
      const auto j = static_cast<std::size_t>(std::countr_zero(both));
      const double* row = base + j * stride;
      const double* bj = b + 3 * j;
      const double c0 = dot3(a0, bj), c1 = dot3(a1, bj);
      if ((tile0 & bit) && (tile1 & bit)) {
        for (int p = 0; p < Packets; ++p) {
          const Packet x = load(row + 8 * p);
          sum0[p] += c0 * x;
          sum1[p] += c1 * x;
        }
      } else if (tile0 & bit) {
        for (int p = 0; p < Packets; ++p) sum0[p] += c0 * load(row + 8 * p);
      } else {
        for (int p = 0; p < Packets; ++p) sum1[p] += c1 * load(row + 8 * p);
      }
    }
    for (int p = 0; p < Packets; ++p) store(target0 + 8 * p, sum0[p]);
    for (int p = 0; p < Packets; ++p) store(target1 + 8 * p, sum1[p]);
  }
};
// Rows of more than 8 packets go in pairs: a word's 64 gathered rows of
// 8 packets (32 KB) stay in L1, wider ones are read from L2 (53 KB at order
// 10). Two rows' sums stay in registers in panels of 7 packets (13 at order
// 10: 7 + 6, faster than 8 + 5). For the bunny's bake the projection took
// 34 ms against 49 (1,024 directions) and 127 against 190 (4,096). At
// order 8 (8 packets) pairs took 24 ms against 18 single; at order 6
// (5 packets) 12.9 against 13.3, not worth a second threshold.
constexpr int kPairPanel = 7;
constexpr Eigen::Index kPairedPackets = 9;  // the narrowest rows that go in pairs

// Calls Kernel<P>::run(first_packet, args...) for panels covering `packets`
// packets: whole panels of sizeof...(P) packets, then the rest with its own
// fixed size.
template <template <int> class Kernel, int... P, class... Args>
void for_each_panel(std::integer_sequence<int, P...>, Eigen::Index packets, Args&&... args) {
  constexpr int kPanel = sizeof...(P);
  for (int first = 0; first < packets; first += kPanel) {
    const int width = static_cast<int>(std::min<Eigen::Index>(kPanel, packets - first));
    ((width == P + 1 ? (Kernel<P + 1>::run(first, args...), true) : false) || ...);
  }
}

// out.row(i) (zeroed first) for output rows [first, last) of `m`, over the
// gathered rows of words [first_word, last_word) (default: all).
void masked_sums(const MaskedSums& m, std::size_t first, std::size_t last, PaddedRows& out,
                 Eigen::Index first_out_row, std::size_t first_word = 0,
                 std::size_t last_word = std::size_t(-1)) {
  const Eigen::Index packets = m.rows->stride() / 8;
  for (std::size_t r = first; r < last; ++r)
    std::fill_n(out.row(first_out_row + Eigen::Index(r - first)), out.stride(), 0.0);
  if (packets == 0) return;
  const auto out_row = [&](std::size_t r) {
    return out.row(first_out_row + Eigen::Index(r - first));
  };
  for (std::size_t word = first_word; word < std::min(last_word, m.words); ++word) {
    std::size_t r = first;
    for (; packets >= kPairedPackets && r + 1 < last; r += 2) {
      const std::uint64_t tile0 = m.bits[r * m.words + word];
      const std::uint64_t tile1 = m.bits[(r + 1) * m.words + word];
      if ((tile0 | tile1) == 0) continue;
      for_each_panel<TilePairKernel>(std::make_integer_sequence<int, kPairPanel>(), packets, m,
                                     m.a + 3 * r, m.a + 3 * (r + 1), tile0, tile1, word, out_row(r),
                                     out_row(r + 1));
    }
    for (; r < last; ++r)
      if (const std::uint64_t tile = m.bits[r * m.words + word])
        for_each_panel<TileKernel>(std::make_integer_sequence<int, kMaxPanel>(), packets, m,
                                   m.a + 3 * r, tile, word, out_row(r));
  }
}

// Products along chains of output rows. With c_rj = a_r . b_j (normals / pi
// and directions, one way or the other), output row r is a_r . N_r, where
// N_r = sum over the set bits j of r's bit row of b_j (x) rows.row(j) (3
// rows). Neighbouring output rows have nearly the same bits (for the bunny
// at 6,144 cube-map directions, 6.5% of the visible pairs differ between
// consecutive directions, ~10% between vertices in Morton order), so N_r is
// N_{r'} of the row before it in the chain plus the rows r has and r' has
// not, less the reverse: 3 multiply-adds per differing pair instead of one
// per set bit. Each chain starts with a direct sum, and chains are fixed by
// the caller from the shapes alone (not by tasks, threads or ranks), so a
// row's bits do not depend on them; rounding builds up over kChain steps
// at most.
constexpr std::size_t kChain = 64;
constexpr int kChainPanel = 8;  // 3 x 8 packets of sums in registers

template <int Packets>
struct ChainKernel {
  static void run(int first_packet, const MaskedSums& m, const std::uint32_t* chain,
                  std::size_t length, std::size_t first_word, std::size_t last_word,
                  PaddedRows& out) {
    const auto stride = static_cast<std::size_t>(m.rows->stride());
    const double* base = m.rows->row(0) + 8 * first_packet;
    Packet n[3][Packets];
    // n += sign b_j (x) rows.row(j) for the set bits j of word `word`'s `tile`.
    const auto add = [&](std::uint64_t tile, std::size_t word, double sign) {
      for (; tile; tile &= tile - 1) {
        const std::size_t j = 64 * word + static_cast<std::size_t>(std::countr_zero(tile));
        const double* row = base + j * stride;
        const double bx = sign * m.b[3 * j], by = sign * m.b[3 * j + 1], bz = sign * m.b[3 * j + 2];
        for (int p = 0; p < Packets; ++p) {
          const Packet x = load(row + 8 * p);
          n[0][p] += bx * x;
          n[1][p] += by * x;
          n[2][p] += bz * x;
        }
      }
    };
    for (int c = 0; c < 3; ++c)
      for (int p = 0; p < Packets; ++p) n[c][p] = Packet{};
    for (std::size_t i = 0; i < length; ++i) {
      const std::size_t r = chain[i];
      const std::uint64_t* bits = m.bits + r * m.words;
      if (i == 0) {
        for (std::size_t w = first_word; w < last_word; ++w) add(bits[w], w, 1.0);
      } else {
        const std::uint64_t* before = m.bits + std::size_t(chain[i - 1]) * m.words;
        for (std::size_t w = first_word; w < last_word; ++w) {
          add(bits[w] & ~before[w], w, 1.0);
          add(before[w] & ~bits[w], w, -1.0);
        }
      }
      const double* a = m.a + 3 * r;
      double* target = out.row(Eigen::Index(r)) + 8 * first_packet;
      for (int p = 0; p < Packets; ++p)
        store(target + 8 * p, a[0] * n[0][p] + a[1] * n[1][p] + a[2] * n[2][p]);
    }
  }
};

// out.row(r) for the output rows r of one chain, in its order, over the
// gathered rows of words [first_word, last_word).
void chained_sums(const MaskedSums& m, const std::uint32_t* chain, std::size_t length,
                  PaddedRows& out, std::size_t first_word, std::size_t last_word) {
  for_each_panel<ChainKernel>(std::make_integer_sequence<int, kChainPanel>(), m.rows->stride() / 8,
                              m, chain, length, first_word, std::min(last_word, m.words), out);
}

// Products along trees of output rows, for the bake: as the chains above,
// N_r = sum over r's set bits j of b_j (x) rows.row(j), but each row's sums
// are carried from the one of the kTreeWindow rows before it (in the
// block's order) whose bits differ least, or summed directly when that is
// cheaper (a root). The parents depend on the block's rows and bits alone.
// Sums of the last kTreeWindow rows are kept in a ring of slots.
constexpr std::size_t kTreeWindow = 32;

struct TreeRing {
  std::vector<double> sums;  // (kTreeWindow + 1) slots of 3 padded rows
  std::size_t slot_doubles = 0;
  explicit TreeRing(Eigen::Index stride)
      : sums((kTreeWindow + 1) * 3 * std::size_t(stride)), slot_doubles(3 * std::size_t(stride)) {}
  double* slot(std::size_t position) {
    return sums.data() + position % (kTreeWindow + 1) * slot_doubles;
  }
};

// A row's changes from its parent: the directions to add, then those to
// remove (for a root, all of its set bits), listed once for all panels.
struct TreeChanges {
  std::vector<std::uint32_t> directions;
  std::size_t added = 0;  // directions[0, added) are added, [added, count) removed
  std::size_t count = 0;
};

void list_changes(const MaskedSums& m, std::size_t r, std::ptrdiff_t parent, std::size_t parent_row,
                  TreeChanges& changes) {
  const std::uint64_t* bits = m.bits + r * m.words;
  const std::uint64_t* before = m.bits + parent_row * m.words;
  changes.directions.resize(64 * m.words);  // at most every direction once
  std::uint32_t* to = changes.directions.data();
  const auto list = [&](std::uint64_t tile, std::size_t word) {
    for (; tile; tile &= tile - 1)
      *to++ = std::uint32_t(64 * word) + std::uint32_t(std::countr_zero(tile));
  };
  for (std::size_t w = 0; w < m.words; ++w) list(parent < 0 ? bits[w] : bits[w] & ~before[w], w);
  changes.added = std::size_t(to - changes.directions.data());
  if (parent >= 0)
    for (std::size_t w = 0; w < m.words; ++w) list(before[w] & ~bits[w], w);
  changes.count = std::size_t(to - changes.directions.data());
}

template <int Packets>
struct TreeKernel {
  // Row `r` (at `position` in its block's order), from the sums of `parent`
  // (a position, or -1 for a root) and its changes: its sums into the ring
  // and a_r . N_r into `out_row`.
  static void run(int first_packet, const MaskedSums& m, std::size_t r, std::size_t position,
                  std::ptrdiff_t parent, const TreeChanges& changes, TreeRing& ring,
                  double* out_row) {
    const auto stride = static_cast<std::size_t>(m.rows->stride());
    const double* base = m.rows->row(0) + 8 * first_packet;
    Packet n[3][Packets];
    if (parent < 0) {
      for (int c = 0; c < 3; ++c)
        for (int p = 0; p < Packets; ++p) n[c][p] = Packet{};
    } else {
      const double* from = ring.slot(std::size_t(parent)) + 8 * first_packet;
      for (int c = 0; c < 3; ++c)
        for (int p = 0; p < Packets; ++p) n[c][p] = load(from + c * stride + 8 * p);
    }
    // n += sign b_j (x) rows.row(j) over listed directions [from, to) (the
    // sign is exact: the same bits as subtracting).
    const auto add = [&](std::size_t from, std::size_t to, double sign) {
      for (std::size_t i = from; i < to; ++i) {
        const std::size_t j = changes.directions[i];
        const double* row = base + j * stride;
        const double bx = sign * m.b[3 * j], by = sign * m.b[3 * j + 1], bz = sign * m.b[3 * j + 2];
        for (int p = 0; p < Packets; ++p) {
          const Packet x = load(row + 8 * p);
          n[0][p] += bx * x;
          n[1][p] += by * x;
          n[2][p] += bz * x;
        }
      }
    };
    add(0, changes.added, 1.0);
    add(changes.added, changes.count, -1.0);
    double* to = ring.slot(position) + 8 * first_packet;
    for (int c = 0; c < 3; ++c)
      for (int p = 0; p < Packets; ++p) store(to + c * stride + 8 * p, n[c][p]);
    const double* a = m.a + 3 * r;
    double* target = out_row + 8 * first_packet;
    for (int p = 0; p < Packets; ++p)
      store(target + 8 * p, a[0] * n[0][p] + a[1] * n[1][p] + a[2] * n[2][p]);
  }
};

// The position of row order[i]'s parent among the kTreeWindow before it
// (the first of those whose bits differ least), or -1 when no parent
// differs in fewer bits than the row has set.
std::ptrdiff_t tree_parent(const MaskedSums& m, const std::uint32_t* order, std::size_t i) {
  const std::uint64_t* bits = m.bits + std::size_t(order[i]) * m.words;
  std::size_t least = 0;
  for (std::size_t w = 0; w < m.words; ++w) least += std::size_t(std::popcount(bits[w]));
  std::ptrdiff_t parent = -1;
  for (std::size_t k = i > kTreeWindow ? i - kTreeWindow : 0; k < i; ++k) {
    const std::uint64_t* other = m.bits + std::size_t(order[k]) * m.words;
    std::size_t differ = 0;
    for (std::size_t w = 0; w < m.words; ++w)  // no early exit: vector popcounts
      differ += std::size_t(std::popcount(bits[w] ^ other[w]));
    if (differ < least) least = differ, parent = std::ptrdiff_t(k);
  }
  return parent;
}

// Rows of x, y, z of `count` vectors (the mesh's normals are floats), scaled.
std::vector<double> coordinates(const auto& vectors, std::size_t count, double scale) {
  std::vector<double> xyz(3 * count);
  for (std::size_t i = 0; i < count; ++i)
    for (int c = 0; c < 3; ++c) xyz[3 * i + c] = double(vectors(i, c)) * scale;
  return xyz;
}

void check_rows(Eigen::Index rows, std::size_t expected, const char* what, const char* of) {
  if (rows != static_cast<Eigen::Index>(expected))
    throw Error(std::string(what) + " has " + std::to_string(rows) + " rows for " +
                std::to_string(expected) + " " + of);
}

// The bits' vertices [first, first + count) must be the mesh's.
void check_range(const Mesh& mesh, std::size_t first, std::size_t count, const char* what) {
  if (first > mesh.vertex_count() || count > mesh.vertex_count() - first)
    throw Error(std::string(what) + ": visibility of vertices [" + std::to_string(first) + ", " +
                std::to_string(first + count) + ") for a mesh of " +
                std::to_string(mesh.vertex_count()) + " vertices");
}

}  // namespace

void visible_times(const Mesh& mesh, const DirectionSet& set, const std::uint32_t* vertices,
                   std::size_t count, const std::uint64_t* bits, const PaddedRows& right,
                   PaddedRows& out) {
  const auto s = static_cast<std::size_t>(set.size());
  check_rows(right.rows(), s, "visible_times: the right-hand matrix", "directions");
  const std::size_t words = VisibilityBits::words_for(s);
  const auto normal = [&](std::size_t i, int c) { return mesh.normals[vertices[i]][c]; };
  const std::vector<double> a = coordinates(normal, count, 1 / M_PI);
  out = PaddedRows(static_cast<Eigen::Index>(count), right.cols());
  masked_sums({bits, words, a.data(), set.directions.data(), &right}, 0, count, out, 0);
}

void visible_times_in_blocks(const Mesh& mesh, const DirectionSet& set, std::size_t first,
                             std::size_t last, const std::uint64_t* bits, const PaddedRows& right,
                             float* out, std::size_t out_stride) {
  const auto s = static_cast<std::size_t>(set.size());
  check_rows(right.rows(), s, "visible_times_in_blocks: the right-hand matrix", "directions");
  if (last < first)
    throw Error("visible_times_in_blocks: vertices [" + std::to_string(first) + ", " +
                std::to_string(last) + ") end before they start");
  check_range(mesh, first, last - first, "visible_times_in_blocks");
  if (last == first) return;
  const auto normal = [&](std::size_t i, int c) { return mesh.normals[first + i][c]; };
  const std::vector<double> a = coordinates(normal, last - first, 1 / M_PI);
  const MaskedSums m{bits, VisibilityBits::words_for(s), a.data(), set.directions.data(), &right};
  const Eigen::Index packets = right.stride() / 8, cols = right.cols();
  // The range's rows along the whole mesh's Morton curve, then by block,
  // each block's in curve order (a stable sort): the curve of each block.
  std::vector<std::uint32_t> curve = morton_order(mesh, first, last);
  for (std::uint32_t& v : curve) v -= std::uint32_t(first);  // rows of `bits`
  const auto block_of = [&](std::uint32_t r) { return (first + r) / kProjectionBlock; };
  std::stable_sort(curve.begin(), curve.end(),
                   [&](std::uint32_t x, std::uint32_t y) { return block_of(x) < block_of(y); });
  for_each_row_block(first, last, kProjectionBlock, [&](std::size_t begin, std::size_t end) {
    const std::uint32_t* order = curve.data() + (begin - first);  // the block's rows
    const std::size_t count = end - begin;
    TreeRing ring(right.stride());
    TreeChanges changes;
    std::vector<double> row(std::size_t(right.stride()));
    for (std::size_t i = 0; i < count; ++i) {
      const std::size_t r = order[i];
      const std::ptrdiff_t parent = tree_parent(m, order, i);
      list_changes(m, r, parent, parent < 0 ? r : std::size_t(order[std::size_t(parent)]), changes);
      for_each_panel<TreeKernel>(std::make_integer_sequence<int, kChainPanel>(), packets, m, r, i,
                                 parent, changes, ring, row.data());
      float* target = out + r * out_stride;
      for (Eigen::Index c = 0; c < cols; ++c) target[c] = static_cast<float>(row[std::size_t(c)]);
    }
  });
}

void visible_times(const Mesh& mesh, const DirectionSet& set, const VisibilityBits& visibility,
                   const PaddedRows& right, PaddedRows& out, std::size_t first_vertex) {
  const auto s = static_cast<std::size_t>(set.size());
  check_rows(right.rows(), s, "visible_times: the right-hand matrix", "directions");
  check_range(mesh, first_vertex, visibility.vertices(), "visible_times");
  check_rows(set.size(), visibility.directions(), "visible_times: the direction set",
             "directions of visibility");
  const auto normal = [&](std::size_t i, int c) { return mesh.normals[first_vertex + i][c]; };
  const std::vector<double> a = coordinates(normal, visibility.vertices(), 1 / M_PI);
  if (out.rows() != Eigen::Index(visibility.vertices()) || out.cols() != right.cols())
    out = PaddedRows(Eigen::Index(visibility.vertices()), right.cols());
  const MaskedSums m{visibility.words(0), VisibilityBits::words_for(s), a.data(),
                     set.directions.data(), &right};
  // Chains of kChain vertices along the Morton curve of each segment's
  // vertices (segments of the whole mesh, as segment_sum's, so that a rank's
  // shard holds whole chains): neighbours in space see nearly the same
  // directions, where neighbours in the file differ in ~30% of their pairs.
  const std::size_t count = visibility.vertices();
  const auto segment = [&](std::uint32_t v) {  // of a local vertex
    return (first_vertex + v) / std::size_t(kSegmentRows);
  };
  // The shard's vertices along the whole mesh's curve, then split by segment,
  // each segment's in curve order (a stable sort).
  std::vector<std::uint32_t> order = morton_order(mesh, first_vertex, first_vertex + count);
  for (std::uint32_t& v : order) v -= std::uint32_t(first_vertex);  // local indices
  std::stable_sort(order.begin(), order.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return segment(a) < segment(b); });
  std::vector<std::size_t> starts;  // chains: kChain vertices, none across segments
  for (std::size_t i = 0; i < count; ++i)
    if (starts.empty() || i - starts.back() == kChain || segment(order[i]) != segment(order[i - 1]))
      starts.push_back(i);
  starts.push_back(count);
  tbb::parallel_for(std::size_t(0), starts.size() - 1, [&](std::size_t c) {
    chained_sums(m, order.data() + starts[c], starts[c + 1] - starts[c], out, 0, m.words);
  });
}

Eigen::MatrixXd visible_times(const Mesh& mesh, const DirectionSet& set,
                              const VisibilityBits& visibility, const Eigen::MatrixXd& right) {
  PaddedRows out;
  visible_times(mesh, set, visibility, PaddedRows(right), out);
  return out.matrix();
}

void visible_transpose_times(const Mesh& mesh, const DirectionSet& set,
                             const TransposedVisibility& transposed, const PaddedRows& left,
                             PaddedRows& out) {
  const auto s = static_cast<std::size_t>(set.size());
  check_rows(left.rows(), transposed.vertices(), "visible_transpose_times: the left matrix",
             "vertices");
  check_rows(set.size(), transposed.directions(), "visible_transpose_times: the direction set",
             "directions of visibility");
  check_rows(Eigen::Index(mesh.vertex_count()), transposed.vertices(),
             "visible_transpose_times: the mesh", "vertices of visibility");
  // a . b = d . (n / pi): the same products, rounded alike, as T's own.
  const auto normal = [&](std::size_t i, int c) { return mesh.normals[i][c]; };
  const std::vector<double> b = coordinates(normal, mesh.vertex_count(), 1 / M_PI);
  const MaskedSums m{transposed.words(0), transposed.words_per_direction(), set.directions.data(),
                     b.data(), &left};
  if (out.rows() != set.size() || out.cols() != left.cols())
    out = PaddedRows(set.size(), left.cols());
  // Each output row sums its vertices in order: any split of the rows
  // among threads gives the same bits. Tasks of up to 512 directions: each
  // reads all of `left` once (as a tile of 64 vertices at a time, in L1),
  // with its output rows in L2.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, s, 512), [&](const auto& range) {
    masked_sums(m, range.begin(), range.end(), out, Eigen::Index(range.begin()));
  });
}

Eigen::MatrixXd visible_transpose_times(const Mesh& mesh, const DirectionSet& set,
                                        const TransposedVisibility& transposed,
                                        const Eigen::MatrixXd& left) {
  PaddedRows out;
  visible_transpose_times(mesh, set, transposed, PaddedRows(left), out);
  return out.matrix();
}

Eigen::MatrixXd visible_transpose_times(const Mesh& mesh, const DirectionSet& set,
                                        const VisibilityBits& visibility,
                                        const Eigen::MatrixXd& left) {
  return visible_transpose_times(mesh, set, TransposedVisibility(visibility), left);
}

Eigen::MatrixXd visible_transpose_sum(const Mesh& mesh, const DirectionSet& set,
                                      const TransposedVisibility& transposed,
                                      const PaddedRows& left, const RowParts& parts) {
  const Shard shard = parts.shard();
  const auto s = static_cast<std::size_t>(set.size());
  check_rows(left.rows(), transposed.vertices(), "visible_transpose_sum: the left matrix",
             "vertices");
  check_rows(shard.rows(), transposed.vertices(), "visible_transpose_sum: the shard",
             "vertices of visibility");
  check_rows(set.size(), transposed.directions(), "visible_transpose_sum: the direction set",
             "directions of visibility");
  check_range(mesh, std::size_t(shard.first), transposed.vertices(), "visible_transpose_sum");
  const auto normal = [&](std::size_t i, int c) {
    return mesh.normals[std::size_t(shard.first) + i][c];
  };
  const std::vector<double> b = coordinates(normal, transposed.vertices(), 1 / M_PI);
  const MaskedSums m{transposed.words(0), transposed.words_per_direction(), set.directions.data(),
                     b.data(), &left};
  const Eigen::Index cols = left.cols();
  // A segment's words: shards start at whole segments, and segments are
  // whole words (kSegmentRows is a multiple of 64).
  static_assert(kSegmentRows % 64 == 0);
  const auto partial = [&](Eigen::Index segment) {
    const auto begin = std::size_t(segment_begin(segment) - shard.first),
               end = std::size_t(segment_end(segment, shard.total) - shard.first);
    PaddedRows sums(set.size(), cols);
    // Chains of kChain consecutive directions.
    const std::size_t chains = (s + kChain - 1) / kChain;
    tbb::parallel_for(std::size_t(0), chains, [&](std::size_t c) {
      std::uint32_t chain[kChain];
      const std::size_t length = std::min(kChain, s - c * kChain);
      for (std::size_t i = 0; i < length; ++i) chain[i] = std::uint32_t(c * kChain + i);
      chained_sums(m, chain, length, sums, begin / 64, (end + 63) / 64);
    });
    std::vector<double> values(s * std::size_t(cols));
    Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
        values.data(), set.size(), cols) = sums.matrix_view();
    return values;
  };
  const std::vector<double> sum = parts.sum(partial);
  if (sum.empty()) return Eigen::MatrixXd::Zero(set.size(), cols);
  return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      sum.data(), set.size(), cols);
}

}  // namespace prt
