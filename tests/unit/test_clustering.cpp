#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <catch2/catch.hpp>
#include <limits>
#include <map>
#include <numeric>
#include <random>
#include <set>

#include "../../plugins/compressor/clustering/classify_kernel.hpp"
#include "../../plugins/compressor/clustering/first_minimum.hpp"
#include "../../plugins/compressor/clustering/lower_product.hpp"
#include "prt/clustering.hpp"
#include "prt/compressor.hpp"

using namespace prt;
using namespace prt::clustering;

namespace {
// `clusters` well-separated blobs in n dimensions, each of low rank.
MatrixXfRow blobs(int points, int n, int clusters, std::uint64_t seed, float spread = 0.05f,
                  float axis_scale = 1.0f) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> g;
  MatrixXfRow centres(clusters, n), axes(clusters, n);
  for (auto& v : centres.reshaped()) v = 3.f * g(rng);
  for (auto& v : axes.reshaped()) v = g(rng);
  MatrixXfRow x(points, n);
  for (int p = 0; p < points; ++p) {
    const int k = p % clusters;
    x.row(p) = centres.row(k) + axis_scale * g(rng) * axes.row(k);
    for (int d = 0; d < n; ++d) x(p, d) += spread * g(rng);
  }
  return x;
}

double se_of(const MatrixXfRow& x, const CompressedTransfer& c) {
  return squared_error(x, c.decode());
}
}  // namespace

TEST_CASE("LBG separates well-separated blobs with either start", "[clustering]") {
  const MatrixXfRow x = blobs(800, 12, 8, 1, 0.3f, 0.0f);  // round, well apart
  for (Init init : {Init::kmeans_plus_plus, Init::hyperbox}) {
    LbgOptions o;
    o.clusters = 8;
    o.init = init;
    o.max_iterations = 100;
    const Clusters c = lbg(x, o);
    std::vector<std::set<int>> labels_of_blob(8);
    for (int p = 0; p < 800; ++p) labels_of_blob[p % 8].insert(c.labels[p]);
    int pure = 0;
    for (const auto& s : labels_of_blob) pure += s.size() == 1;
    INFO("init " << int(init));
    CHECK(pure == 8);
    CHECK(c.means.allFinite());
  }
}

TEST_CASE("LBG is deterministic for a seed and handles its extremes", "[clustering][extremes]") {
  const MatrixXfRow x = blobs(300, 6, 5, 2);
  LbgOptions o;
  o.clusters = 5;
  CHECK(lbg(x, o).labels == lbg(x, o).labels);
  // One cluster per point: zero energy.
  o.clusters = 300;
  CHECK(lbg(x, o).energy < 1e-9);
  // More clusters than points, identical points, one point: no NaN.
  const MatrixXfRow same = MatrixXfRow::Constant(10, 4, 0.5f);
  o.clusters = 16;
  const Clusters c = lbg(same, o);
  CHECK(c.energy == 0.0);
  CHECK(c.means.allFinite());
  const Clusters one = lbg(MatrixXfRow::Constant(1, 3, 2.f), o);
  CHECK(one.means.rows() == 1);
  CHECK(one.means(0, 0) == 2.0);
}

TEST_CASE("16k clusters run without empty clusters", "[clustering][extremes]") {
  const MatrixXfRow x = blobs(20000, 8, 50, 3, 0.3f);
  LbgOptions o;
  o.clusters = 16384;
  o.max_iterations = 2;
  const Clusters c = lbg(x, o);
  std::vector<int> count(16384, 0);
  for (auto l : c.labels) ++count[l];
  CHECK(*std::min_element(count.begin(), count.end()) >= 1);
}

TEST_CASE("cluster PCA: orthonormal, exact at full rank, safe when degenerate",
          "[clustering][extremes]") {
  const MatrixXfRow x = blobs(200, 10, 1, 4, 0.3f);
  std::vector<std::uint32_t> all(200);
  std::iota(all.begin(), all.end(), 0u);
  const ClusterModel full = fit_cluster(x, all, 10);
  CHECK((full.basis * full.basis.transpose() - Eigen::MatrixXd::Identity(10, 10))
            .cwiseAbs()
            .maxCoeff() < 1e-9);
  for (int p = 0; p < 200; ++p) CHECK(approximation_error(x, p, full) < 1e-9);
  // Eigenvalues descending and equal to the captured energy.
  for (int i = 1; i < 10; ++i) CHECK(full.eigenvalues[i] <= full.eigenvalues[i - 1]);
  // Fewer points than components (C C^T side): exact, extra rows zero.
  const std::vector<std::uint32_t> three{0, 1, 2};
  const ClusterModel small = fit_cluster(x, three, 8);
  CHECK(small.basis.allFinite());
  CHECK(small.basis.row(7).norm() == 0.0);
  for (auto p : three) CHECK(approximation_error(x, p, small) < 1e-9);
  // Identical points and an empty cluster.
  const MatrixXfRow same = MatrixXfRow::Constant(5, 4, 1.f);
  const ClusterModel flat = fit_cluster(same, {0, 1, 2, 3, 4}, 3);
  CHECK(flat.basis.cwiseAbs().maxCoeff() == 0.0);
  CHECK(flat.mean.isApprox(Eigen::RowVectorXd::Ones(4)));
  CHECK(fit_cluster(same, {}, 3).mean.allFinite());
}

// The direct PCA of rows `members` of x: the scatter about the mean in double,
// all its eigenpairs, largest first.
std::pair<Eigen::VectorXd, Eigen::MatrixXd> direct_pca(const MatrixXfRow& x,
                                                       const std::vector<std::uint32_t>& members) {
  Eigen::RowVectorXd mean = Eigen::RowVectorXd::Zero(x.cols());
  for (auto p : members) mean += x.row(p).cast<double>();
  mean /= double(members.size());
  Eigen::MatrixXd scatter = Eigen::MatrixXd::Zero(x.cols(), x.cols());
  for (auto p : members) {
    const Eigen::RowVectorXd d = x.row(p).cast<double>() - mean;
    scatter += d.transpose() * d;
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(scatter);
  return {solver.eigenvalues().reverse(), solver.eigenvectors().rowwise().reverse()};
}

TEST_CASE("a cluster's PCA is the direct one whether its members are gathered or not",
          "[clustering]") {
  // 6 dimensions: a cluster of fewer than 6 points is fitted from its Gram
  // matrix, one of at most kGatheredPointsPerDimension * 6 from its scatter,
  // both of its gathered members; a larger one has its scatter summed over
  // segments.
  constexpr int n = 6;
  const MatrixXfRow x = blobs(3000, n, 1, 11, 0.2f);
  REQUIRE(kGatheredPointsPerDimension * n < 3000);
  for (int points : {5, kGatheredPointsPerDimension * n, 3000}) {
    INFO(points << " points");
    std::vector<std::uint32_t> members(static_cast<std::size_t>(points));
    std::iota(members.begin(), members.end(), 0u);
    const ClusterModel model = fit_cluster(x, members, n - 1);
    const auto [values, vectors] = direct_pca(x, members);
    for (int i = 0; i < std::min(n, points) - 1; ++i) {  // 5 points: rank 4
      CHECK(std::abs(model.eigenvalues[i] - values[i]) <= 1e-9 * values[0]);
      CHECK(std::abs(model.basis.row(i).dot(vectors.col(i))) == Approx(1.0).epsilon(1e-9));
    }
  }
}

TEST_CASE("iterative CPCA beats static, adaptive beats iterative at equal storage",
          "[clustering][cpca]") {
  const MatrixXfRow x = blobs(3000, 24, 40, 5, 0.2f);
  CpcaOptions o;
  o.lbg.clusters = 16;
  o.components = 3;
  auto run = [&](Method m) {
    o.method = m;
    const CpcaResult r = cpca(x, o);
    return assemble(x, r.labels, r.models, "cpca");
  };
  const CompressedTransfer s = run(Method::static_pca), i = run(Method::iterative),
                           a = run(Method::adaptive);
  CHECK(se_of(x, i) < se_of(x, s));
  CHECK(se_of(x, a) < se_of(x, i));
  CHECK(a.stored_floats() <= i.stored_floats());
  CHECK(i.stored_floats() == s.stored_floats());
}

TEST_CASE("overdraw counts distinct clusters per triangle", "[clustering][coherence]") {
  Mesh m = make_plane(1);  // 4 vertices, 2 triangles
  CHECK(average_overdraw(m, {0, 0, 0, 0}) == 1.0);
  CHECK(average_overdraw(m, {0, 1, 2, 3}) == 3.0);
}

TEST_CASE("reclassification stays within its error budget and lowers overdraw",
          "[clustering][coherence]") {
  const Mesh sphere = make_sphere(3);
  // A smooth signal over the sphere: clusters follow it, but boundaries are ragged.
  MatrixXfRow x(sphere.vertex_count(), 6);
  std::mt19937_64 rng(6);
  std::normal_distribution<float> noise;
  for (std::size_t v = 0; v < sphere.vertex_count(); ++v) {
    const Eigen::Vector3f p = sphere.positions[v];
    x.row(v) << p.x(), p.y(), p.z(), p.x() * p.y(), p.y() * p.z(), 0.f;
    for (int d = 0; d < 6; ++d) x(v, d) += 0.2f * noise(rng);
  }
  CpcaOptions o;
  o.lbg.clusters = 24;
  o.components = 1;
  const CpcaResult r = cpca(x, o);
  CompressedTransfer c = assemble(x, r.labels, r.models, "cpca");
  const double se_before = se_of(x, c),
               overdraw_before = average_overdraw(sphere, c.cluster_of_vertex);
  const std::size_t moved = reclassify(x, sphere, 0.05, c);
  CHECK(moved > 0);
  CHECK(se_of(x, c) <= 1.05 * se_before + 1e-9);
  CHECK(average_overdraw(sphere, c.cluster_of_vertex) < overdraw_before);
  c.validate(static_cast<Eigen::Index>(sphere.vertex_count()));

  for (auto method : {SuperclusterMethod::greedy_merge, SuperclusterMethod::chen_selection}) {
    CompressedTransfer s = c;
    supercluster(sphere, 5, method, s);
    std::map<int, int> size;
    for (auto id : s.supercluster_of_cluster) ++size[id];
    for (const auto& [id, count] : size) CHECK(count <= 5);
    CHECK(average_overdraw(sphere, supercluster_of_vertex(s)) <
          average_overdraw(sphere, s.cluster_of_vertex));
    CHECK(se_of(x, s) == se_of(x, c));  // superclusters do not change the approximation
  }
}

TEST_CASE("PCA from the Gram matrix (fewer points than dimensions) equals the SVD",
          "[clustering][extremes]") {
  for (int members : {2, 7, 29, 31, 60}) {  // below, near and above n = 30
    INFO(members << " members in 30 dimensions");
    const MatrixXfRow x = blobs(members, 30, 1, std::uint64_t(members), 0.3f);
    std::vector<std::uint32_t> all(static_cast<std::size_t>(members));
    std::iota(all.begin(), all.end(), 0u);
    const ClusterModel model = fit_cluster(x, all, 5);
    const Eigen::MatrixXd centred = x.cast<double>().rowwise() - x.cast<double>().colwise().mean();
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(centred, Eigen::ComputeThinV);
    const Eigen::Index rank = std::min<Eigen::Index>(5, members - 1);
    for (Eigen::Index i = 0; i < rank; ++i) {
      const double sigma = svd.singularValues()[i];
      CHECK(model.eigenvalues[i] == Approx(sigma * sigma).epsilon(1e-10));
      CHECK(std::abs(model.basis.row(i).dot(svd.matrixV().col(i))) == Approx(1).epsilon(1e-8));
    }
    for (Eigen::Index i = rank; i < 5; ++i) CHECK(model.basis.row(i).isZero());
  }
}

TEST_CASE("a refit keeps the models of unchanged clusters and refits the others", "[clustering]") {
  const MatrixXfRow x = blobs(400, 12, 4, 5);
  std::vector<std::int32_t> labels(400);
  for (int p = 0; p < 400; ++p) labels[std::size_t(p)] = p % 4;
  const Rows rows(x);
  const auto first = fit_models(rows, labels, 4, {3, 3, 3, 3});
  std::vector<std::int32_t> moved = labels;
  moved[1] = 2;  // point 1 leaves cluster 1 for cluster 2
  FitReuse reuse{&first, changed_clusters(rows, labels, moved, 4), 3};
  CHECK(reuse.changed == std::vector<char>{0, 1, 1, 0});
  // Mark the kept models so that reuse is visible.
  std::vector<ClusterModel> marked = first;
  for (auto& m : marked) m.eigenvalues[0] = -1;
  reuse.previous = &marked;
  const auto second = fit_models(rows, moved, 4, {3, 3, 3, 3}, nullptr, &reuse);
  const auto fresh = fit_models(rows, moved, 4, {3, 3, 3, 3});
  CHECK(second[0].eigenvalues[0] == -1);
  CHECK(second[3].eigenvalues[0] == -1);
  CHECK(second[1].basis == fresh[1].basis);
  CHECK(second[2].basis == fresh[2].basis);
  CHECK(second[1].eigenvalues[0] > 0);
  // A kept model with too few directions is refitted.
  reuse.minimum = 4;
  const auto wider = fit_models(rows, moved, 4, {4, 4, 4, 4}, nullptr, &reuse);
  CHECK(wider[0].eigenvalues[0] > 0);
  CHECK(wider[0].basis.rows() == 4);
}

TEST_CASE("first_minimum: the first smallest, as a scalar scan with <", "[clustering][extremes]") {
  const auto scalar = [](const std::vector<float>& v) {
    float best = std::numeric_limits<float>::infinity();
    int at = 0;
    for (std::size_t j = 0; j < v.size(); ++j)
      if (v[j] < best) best = v[j], at = static_cast<int>(j);
    return at;
  };
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<int> small(0, 5);  // few values: many ties
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  for (int count = 0; count <= 70; ++count)
    for (int trial = 0; trial < 20; ++trial) {
      std::vector<float> v(static_cast<std::size_t>(count));
      for (float& x : v) x = float(small(rng)) - 2.5f;
      if (count > 0 && trial % 4 == 1) v[std::size_t(trial) % v.size()] = nan;  // NaN is skipped
      if (count > 0 && trial % 4 == 2) v.assign(v.size(), inf);                 // all infinite
      if (count > 0 && trial % 4 == 3) v.assign(v.size(), nan);                 // all NaN
      INFO("count " << count << ", trial " << trial);
      CHECK(first_minimum(v.data(), count) == scalar(v));
    }
  // A NaN in the first 16 lanes does not hide a later minimum in that lane.
  std::vector<float> v(40, 1.f);
  v[3] = nan;
  v[19] = -1.f;  // lane 3 of the second packet
  CHECK(first_minimum(v.data(), 40) == 19);
}

TEST_CASE("the packed classification picks the cluster of least approximation error",
          "[clustering][extremes]") {
  // Sizes that leave partial groups of 16 clusters, partial tiles of 4 rows
  // and one to three passes over the component panels; some clusters have
  // fewer directions than asked, some none.
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g;
  for (const int n : {3, 100})
    for (const int k : {1, 16, 37})
      for (const int asked : {0, 1, 5, 6, 8, 11, 13}) {
        const int points = 23;
        std::vector<ClusterModel> models(static_cast<std::size_t>(k));
        for (int j = 0; j < k; ++j) {
          // One direction more than asked where there is room (as a refit
          // fits), fewer for some, and a last group of narrow clusters.
          const int count =
              std::min(n, j % 3 == 2 ? asked / 2 + 1 : (j >= 32 ? std::min(asked, 1) : asked + 1));
          Eigen::MatrixXd q = Eigen::MatrixXd::NullaryExpr(n, n, [&] { return g(rng); });
          q = Eigen::HouseholderQR<Eigen::MatrixXd>(q).householderQ();
          models[std::size_t(j)] = {
              Eigen::RowVectorXd::NullaryExpr(n, [&] { return 0.3 * g(rng); }),
              q.leftCols(count).transpose(), Eigen::VectorXd::Ones(count)};
        }
        MatrixXfRow x(points, n);
        for (int p = 0; p < points; ++p) {  // along one cluster's directions
          const ClusterModel& m = models[std::size_t(p % k)];
          // Most of it along the last directions, which the last pass adds.
          Eigen::VectorXd along(m.basis.rows());
          for (Eigen::Index t = 0; t < along.size(); ++t) along[t] = double(1 + t) * g(rng);
          x.row(p) = (m.mean + along.transpose() * m.basis +
                      0.05 * Eigen::RowVectorXd::NullaryExpr(n, [&] {
                        return g(rng);
                      })).cast<float>();
        }
        const PackedClassifier packed = pack_classifier(models, asked);
        std::vector<std::int32_t> labels(points, -1), split(points, -1);
        std::vector<float> scratch;
        classify_rows(x, 0, points, packed, labels.data(), scratch);
        // A row's label does not depend on the block it is classified in.
        classify_rows(x, 0, 5, packed, split.data(), scratch);
        classify_rows(x, 5, points, packed, split.data() + 5, scratch);
        CHECK(split == labels);
        for (int p = 0; p < points; ++p) {
          std::vector<double> error(static_cast<std::size_t>(k));
          for (int j = 0; j < k; ++j) {
            const ClusterModel& m = models[std::size_t(j)];
            const Eigen::RowVectorXd d = x.row(p).cast<double>() - m.mean;
            const Eigen::Index used = std::min<Eigen::Index>(asked, m.basis.rows());
            error[std::size_t(j)] =
                d.squaredNorm() - (m.basis.topRows(used) * d.transpose()).squaredNorm();
          }
          const double best = *std::min_element(error.begin(), error.end());
          INFO("n " << n << ", k " << k << ", components " << asked << ", row " << p);
          REQUIRE(labels[std::size_t(p)] >= 0);
          REQUIRE(labels[std::size_t(p)] < k);
          // Float rounding of |x|^2 - 2 x.m + |m|^2 may swap near ties only.
          CHECK(error[std::size_t(labels[std::size_t(p)])] <= best + 1e-4 * (1 + 4 * n));
        }
      }
}

TEST_CASE("lower_product is A^T A, exactly symmetric, for any width and depth",
          "[clustering][extremes]") {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g;
  for (const Eigen::Index width : {0, 1, 7, 8, 9, 23, 24, 25, 150})
    for (const Eigen::Index depth : {0, 1, 5, 600}) {
      const Eigen::Index stride = (width + 7) / 8 * 8;
      std::vector<double> a(std::size_t(depth * stride), 0.0);
      Eigen::MatrixXd dense(depth, width);
      for (Eigen::Index i = 0; i < depth; ++i)
        for (Eigen::Index j = 0; j < width; ++j)
          a[std::size_t(i * stride + j)] = dense(i, j) = g(rng);
      Eigen::MatrixXd out = Eigen::MatrixXd::Constant(3, 3, 7.0);  // resized, overwritten
      lower_product(a.data(), depth, width, stride, out);
      INFO("width " << width << ", depth " << depth);
      REQUIRE(out.rows() == width);
      REQUIRE(out.cols() == width);
      if (width == 0) continue;
      const Eigen::MatrixXd direct = dense.transpose() * dense;
      CHECK((out - direct).cwiseAbs().maxCoeff() <= 1e-12 * (1.0 + double(depth)));
      CHECK(out == out.transpose());
    }
}

TEST_CASE("classification over kept errors labels as a full one when some models change",
          "[clustering]") {
  // 37 clusters (three groups, the last partial), 3 directions each; the
  // errors are kept, then some models change and only theirs are packed.
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g;
  const int n = 20, k = 37, points = 301, components = 3;
  const auto model = [&] {
    Eigen::MatrixXd q = Eigen::MatrixXd::NullaryExpr(n, n, [&] { return g(rng); });
    q = Eigen::HouseholderQR<Eigen::MatrixXd>(q).householderQ();
    return ClusterModel{Eigen::RowVectorXd::NullaryExpr(n, [&] { return g(rng); }),
                        q.leftCols(components + 1).transpose(),
                        Eigen::VectorXd::Ones(components + 1)};
  };
  std::vector<ClusterModel> models;
  for (int j = 0; j < k; ++j) models.push_back(model());
  const MatrixXfRow x =
      (Eigen::MatrixXd::NullaryExpr(points, n, [&] { return g(rng); }) * 1.5).cast<float>();
  std::vector<int> all(k);
  std::iota(all.begin(), all.end(), 0);
  std::vector<float> kept(std::size_t(points) * k), scratch;
  std::vector<std::int32_t> labels(points), want(points);
  classify_rows_kept(x, 0, points, pack_classifier(models, components), all, kept.data(), k,
                     labels.data(), scratch);
  classify_rows(x, 0, points, pack_classifier(models, components), want.data(), scratch);
  CHECK(labels == want);
  // Clusters in the first, middle and last group change; the rest keep
  // their errors. Blocks of rows as the classification takes them.
  const std::vector<int> changed{0, 17, 18, 36};
  std::vector<ClusterModel> subset;
  for (int j : changed) {
    models[std::size_t(j)] = model();
    subset.push_back(models[std::size_t(j)]);
  }
  const PackedClassifier packed = pack_classifier(subset, components);
  for (int begin = 0; begin < points; begin += 64) {
    const int end = std::min(points, begin + 64);
    classify_rows_kept(x, begin, end, packed, changed, kept.data() + std::size_t(begin) * k, k,
                       labels.data() + begin, scratch);
  }
  classify_rows(x, 0, points, pack_classifier(models, components), want.data(), scratch);
  CHECK(labels == want);
  long moved = 0;
  for (int p = 0; p < points; ++p)
    moved += std::find(changed.begin(), changed.end(), want[std::size_t(p)]) != changed.end();
  CHECK(moved > 0);  // the changed clusters win some rows
  // Nothing changed: no clusters packed, the labels from the kept errors.
  classify_rows_kept(x, 0, points, pack_classifier({}, components), {}, kept.data(), k,
                     labels.data(), scratch);
  CHECK(labels == want);
  CHECK_THROWS_WITH(
      classify_rows_kept(x, 0, points, packed, all, kept.data(), k, labels.data(), scratch),
      Catch::Contains("37 cluster indices for 4 packed clusters"));
}

TEST_CASE("the packed classification keeps the first of equal clusters and checks the dimension",
          "[clustering][extremes]") {
  // Clusters 3 and 19 (lane 3 of the first and second groups) are the same
  // model: the first wins, as a scalar scan with < keeps it.
  std::vector<ClusterModel> models(20);
  for (int j = 0; j < 20; ++j)
    models[std::size_t(j)] = {Eigen::RowVectorXd::Constant(5, 10.0 + j), RowMatrixXd::Zero(1, 5),
                              Eigen::VectorXd::Ones(1)};
  models[19] = models[3];
  models[3].basis(0, 0) = models[19].basis(0, 0) = 1;
  MatrixXfRow x = MatrixXfRow::Constant(6, 5, 13.f);
  const PackedClassifier packed = pack_classifier(models, 1);
  std::vector<std::int32_t> labels(6, -1);
  std::vector<float> scratch;
  classify_rows(x, 0, 6, packed, labels.data(), scratch);
  CHECK(labels == std::vector<std::int32_t>(6, 3));
  classify_rows(x, 2, 2, packed, labels.data(), scratch);  // no rows: nothing written
  CHECK(labels == std::vector<std::int32_t>(6, 3));
  const MatrixXfRow wrong = MatrixXfRow::Zero(2, 4);
  CHECK_THROWS_WITH(classify_rows(wrong, 0, 2, packed, labels.data(), scratch),
                    Catch::Contains("rows of 4 values") && Catch::Contains("models of 5"));
}
