// The sparse visibility products against dense products of the transport rows.
#include <tbb/global_control.h>

#include <catch2/catch.hpp>

#include "../common/scenes.hpp"
#include "../common/thread_communicator.hpp"
#include "prt/communicator_parts.hpp"
#include "prt/transfer.hpp"
#include "prt/transport.hpp"
#include "prt/visible_products.hpp"

using namespace prt;

namespace {
double relative_error(const Eigen::MatrixXd& got, const Eigen::MatrixXd& want) {
  return (got - want).norm() / std::max(want.norm(), 1e-300);
}
}  // namespace

TEST_CASE("visible products equal dense products of the transport rows", "[visible]") {
  // More than 64 vertices (several blocks) and 6 x 5 x 5 = 150 directions
  // (a partial last word).
  const Mesh scene = test::sphere_over_plane();
  const DirectionSet set = DirectionSet::cubemap(5);
  const TransportResult traced = test::trace_visibility_only(scene, set);
  REQUIRE(scene.vertex_count() > 200);
  Eigen::MatrixXd t;
  transport_rows(scene, set, traced.visibility, 0, scene.vertex_count(), t);
  REQUIRE(t.cwiseAbs().sum() > 0);
  REQUIRE((t.array() == 0).count() > t.size() / 4);  // the kernels must skip real zeros

  // Column counts around the packet (8) and panel (128) sizes, and none.
  for (const Eigen::Index columns : {0, 1, 7, 8, 9, 58, 128, 129, 300}) {
    CAPTURE(columns);
    const Eigen::MatrixXd right = Eigen::MatrixXd::Random(set.size(), columns);
    const Eigen::MatrixXd left = Eigen::MatrixXd::Random(t.rows(), columns);
    const Eigen::MatrixXd product = visible_times(scene, set, traced.visibility, right);
    const Eigen::MatrixXd transposed = visible_transpose_times(scene, set, traced.visibility, left);
    REQUIRE(product.rows() == t.rows());
    REQUIRE(product.cols() == columns);
    REQUIRE(transposed.rows() == t.cols());
    REQUIRE(transposed.cols() == columns);
    CHECK(relative_error(product, t * right) < 1e-13);
    CHECK(relative_error(transposed, t.transpose() * left) < 1e-13);
  }
}

TEST_CASE("visible products give the same bits on one core and on all", "[visible]") {
  const Mesh scene = test::sphere_over_plane();
  const DirectionSet set = DirectionSet::cubemap(8);
  const TransportResult traced = test::trace_visibility_only(scene, set);
  const Eigen::MatrixXd left = Eigen::MatrixXd::Random(scene.vertex_count(), 20);
  const Eigen::MatrixXd right = Eigen::MatrixXd::Random(set.size(), 20);
  const Eigen::MatrixXd all_t = visible_transpose_times(scene, set, traced.visibility, left);
  const Eigen::MatrixXd all = visible_times(scene, set, traced.visibility, right);
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  CHECK(visible_transpose_times(scene, set, traced.visibility, left) == all_t);
  CHECK(visible_times(scene, set, traced.visibility, right) == all);
}

TEST_CASE("visible products of many rows equal each row's own, bit for bit", "[visible]") {
  // A row's sums must not depend on which rows share its call (a kernel that
  // shares a tile's loads between neighbouring rows, or blocks them, must
  // still give each row exactly its own bits, where a partner's bits are
  // clear too). Column counts around the packet (8), the width where rows go
  // in pairs (9 packets) and the pairs' panels (7 packets: 100 columns make
  // 7 + 6, 129 make 7 + 7 + 3); all rows and all but the last (one of the
  // two counts is odd).
  const Mesh scene = test::sphere_over_plane();
  const DirectionSet set = DirectionSet::cubemap(6);
  const TransportResult traced = test::trace_visibility_only(scene, set);
  std::vector<std::uint32_t> vertices(scene.vertex_count());
  for (std::size_t v = 0; v < vertices.size(); ++v) vertices[v] = static_cast<std::uint32_t>(v);
  for (const Eigen::Index columns : {1, 8, 20, 58, 64, 65, 72, 100, 129})
    for (const std::size_t count : {vertices.size(), vertices.size() - 1}) {
      CAPTURE(columns, count);
      const PaddedRows right(Eigen::MatrixXd::Random(set.size(), columns));
      PaddedRows together, alone;
      visible_times(scene, set, vertices.data(), count, traced.visibility.words(0), right,
                    together);
      Eigen::Index differing = 0;
      for (std::size_t v = 0; v < count; ++v) {
        visible_times(scene, set, &vertices[v], 1, traced.visibility.words(v), right, alone);
        differing += (together.block(Eigen::Index(v), 1) != alone.block(0, 1)) ? 1 : 0;
      }
      CHECK(differing == 0);
    }
}

TEST_CASE("visible products over shards: rows of the whole, sums the same bits on any ranks",
          "[visible][distributed]") {
  // Three segments of vertices, the last short, and 6 x 4 x 4 directions.
  const Mesh scene = test::sphere_over_plane(5, 100);
  REQUIRE(scene.vertex_count() > 2 * std::size_t(kSegmentRows));
  const DirectionSet set = DirectionSet::cubemap(4);
  const TransportResult traced = test::trace_visibility_only(scene, set);
  const Eigen::MatrixXd left = Eigen::MatrixXd::Random(scene.vertex_count(), 11);
  const Eigen::MatrixXd right = Eigen::MatrixXd::Random(set.size(), 11);
  const Eigen::MatrixXd whole_product = visible_times(scene, set, traced.visibility, right);
  const Shard all = whole(Eigen::Index(scene.vertex_count()));
  const Eigen::MatrixXd one =
      visible_transpose_sum(scene, set, TransposedVisibility(traced.visibility), PaddedRows(left),
                            *single_part(all.total));
  CHECK(relative_error(one, visible_transpose_times(scene, set, traced.visibility, left)) < 1e-13);
  for (int ranks : {2, 3, 4}) {  // 4: a rank holds no segment
    CAPTURE(ranks);
    std::vector<Eigen::MatrixXd> sums(static_cast<std::size_t>(ranks));
    std::vector<Eigen::MatrixXd> products(static_cast<std::size_t>(ranks));
    test::run_on_ranks(ranks, [&](const Communicator& comm) {
      const Shard shard = shard_of(all.total, comm.rank(), ranks);
      const VisibilityBits bits =
          test::shard_bits(traced.visibility, std::size_t(shard.first), std::size_t(shard.last));
      const PaddedRows rows(Eigen::MatrixXd(left.middleRows(shard.first, shard.rows())));
      sums[std::size_t(comm.rank())] = visible_transpose_sum(scene, set, TransposedVisibility(bits),
                                                             rows, *parts_over(comm, shard));
      PaddedRows out;
      visible_times(scene, set, bits, PaddedRows(right), out, std::size_t(shard.first));
      products[std::size_t(comm.rank())] = out.matrix();
    });
    Eigen::Index at = 0;
    for (int r = 0; r < ranks; ++r) {
      CHECK(sums[std::size_t(r)] == one);  // bit for bit
      const Eigen::Index rows = products[std::size_t(r)].rows();
      CHECK(products[std::size_t(r)] == whole_product.middleRows(at, rows));
      at += rows;
    }
    CHECK(at == all.total);
  }
}

TEST_CASE("the bake's projection in blocks equals dense products, the same bits on any cores",
          "[visible]") {
  // Several blocks of the projection, the last short; 6 x 6 x 6 directions
  // (a partial last word). Rows are carried from neighbours' sums, so a
  // wrong parent, a change left out or a sign would break the dense product.
  const Mesh scene = test::sphere_over_plane(3, 12);
  const std::size_t v = scene.vertex_count();
  REQUIRE(v > 3 * kProjectionBlock);
  REQUIRE(v % kProjectionBlock != 0);
  const DirectionSet set = DirectionSet::cubemap(6);
  const TransportResult traced = test::trace_visibility_only(scene, set);
  Eigen::MatrixXd t;
  transport_rows(scene, set, traced.visibility, 0, v, t);
  REQUIRE((t.array() == 0).count() > t.size() / 4);
  // Columns around the packet (8) and panel (8 packets) sizes.
  for (const Eigen::Index columns : {1, 8, 9, 64, 65, 100, 129}) {
    CAPTURE(columns);
    const Eigen::MatrixXd right = Eigen::MatrixXd::Random(set.size(), columns);
    const PaddedRows padded(right);
    const auto product = [&](std::size_t first, std::size_t last) {
      MatrixXfRow out(Eigen::Index(last - first), columns);
      visible_times_in_blocks(scene, set, first, last, traced.visibility.words(first), padded,
                              out.data(), std::size_t(columns));
      return out;
    };
    const MatrixXfRow all = product(0, v);
    const Eigen::MatrixXd dense = t * right;
    CHECK((all.cast<double>() - dense).cwiseAbs().maxCoeff() <
          1e-6 * std::max(1.0, dense.cwiseAbs().maxCoeff()));
    {
      tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
      CHECK(product(0, v) == all);
    }
    // Ranges of whole blocks (a slab, a shard) get the whole range's rows.
    const std::size_t b = kProjectionBlock;
    CHECK(product(b, v) == all.bottomRows(Eigen::Index(v - b)));
    CHECK(product(b, 3 * b) == all.middleRows(Eigen::Index(b), Eigen::Index(2 * b)));
  }
}

TEST_CASE("the bake's projection in blocks: vertices that see nothing, no columns, bad shapes",
          "[visible]") {
  const Mesh scene = test::sphere_over_plane();
  const std::size_t v = scene.vertex_count();
  const DirectionSet set = DirectionSet::fibonacci(100);
  // Every other vertex sees nothing: roots and parents with no bits.
  VisibilityBits bits = test::trace_visibility_only(scene, set).visibility;
  const std::size_t words = VisibilityBits::words_for(100);
  for (std::size_t i = 0; i < v; i += 2) std::fill_n(bits.words(i), words, 0);
  const Eigen::MatrixXd right = Eigen::MatrixXd::Random(100, 20);
  MatrixXfRow out(Eigen::Index(v), 20);
  visible_times_in_blocks(scene, set, 0, v, bits.words(0), PaddedRows(right), out.data(), 20);
  Eigen::MatrixXd t;
  transport_rows(scene, set, bits, 0, v, t);
  CHECK((out.cast<double>() - t * right).cwiseAbs().maxCoeff() < 1e-5);
  for (std::size_t i = 0; i < v; i += 2) CHECK(out.row(Eigen::Index(i)).isZero(0));
  CHECK(out.allFinite());
  // No columns and no vertices write nothing.
  visible_times_in_blocks(scene, set, 0, v, bits.words(0), PaddedRows(Eigen::MatrixXd(100, 0)),
                          nullptr, 0);
  visible_times_in_blocks(scene, set, 5, 5, bits.words(0), PaddedRows(right), nullptr, 20);
  CHECK_THROWS_WITH(visible_times_in_blocks(scene, set, 0, v, bits.words(0),
                                            PaddedRows(Eigen::MatrixXd(99, 3)), out.data(), 3),
                    Catch::Contains("99 rows for 100"));
  CHECK_THROWS_WITH(visible_times_in_blocks(scene, set, 0, v + 1, bits.words(0), PaddedRows(right),
                                            out.data(), 20),
                    Catch::Contains("for a mesh of"));
  CHECK_THROWS_WITH(
      visible_times_in_blocks(scene, set, 5, 4, bits.words(0), PaddedRows(right), out.data(), 20),
      Catch::Contains("[5, 4) end before they start"));
  // A matrix with a NaN would spread it along the trees: refused by the bake.
  Eigen::MatrixXd poisoned = right;
  poisoned(7, 3) = std::nan("");
  CHECK_THROWS_WITH(diffuse_transfer(scene, set, poisoned, {}, nullptr),
                    Catch::Contains("non-finite") && Catch::Contains("direction 7, coefficient 3"));
}

TEST_CASE("visible products of no vertices are empty", "[visible]") {
  const Mesh empty;
  const DirectionSet set = DirectionSet::cubemap(4);
  const VisibilityBits none(0, static_cast<std::size_t>(set.size()));
  CHECK(visible_times(empty, set, none, Eigen::MatrixXd::Ones(set.size(), 5)).rows() == 0);
  const Eigen::MatrixXd transposed =
      visible_transpose_times(empty, set, none, Eigen::MatrixXd(0, 5));
  CHECK(transposed.rows() == set.size());
  CHECK(transposed.isZero());
}

TEST_CASE("visible products refuse mismatched shapes", "[visible]") {
  const Mesh scene = test::sphere_over_plane();
  const DirectionSet set = DirectionSet::cubemap(4);
  const TransportResult traced = test::trace_visibility_only(scene, set);
  CHECK_THROWS_WITH(visible_times(scene, set, traced.visibility, Eigen::MatrixXd(5, 3)),
                    Catch::Contains("rows for 96 directions"));
  CHECK_THROWS_WITH(visible_transpose_times(scene, set, traced.visibility, Eigen::MatrixXd(5, 3)),
                    Catch::Contains("vertices"));
  // Bits traced over another direction set.
  const DirectionSet other = DirectionSet::cubemap(5);
  CHECK_THROWS_WITH(
      visible_times(scene, other, traced.visibility, Eigen::MatrixXd::Zero(other.size(), 3)),
      Catch::Contains("directions of visibility"));
}
