#include "prt/transfer.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <numeric>

#include "prt/error.hpp"
#include "prt/row_blocks.hpp"

namespace prt {

void CompressedTransfer::decode_row(Eigen::Index p, Eigen::Ref<Eigen::RowVectorXf> out) const {
  const int k = cluster_of_vertex[p];
  out = means.row(k);
  if (sparse()) {
    for (int j = 0; j < components; ++j) out[weight_index[p * components + j]] += weights(p, j);
    return;
  }
  const int n_k = components_of(k);
  if (n_k > 0) out.noalias() += weights.row(p).head(n_k) * representatives[k];
}

MatrixXfRow CompressedTransfer::decode() const {
  MatrixXfRow out(vertices(), dimension);
  tbb::parallel_for(Eigen::Index(0), vertices(),
                    [&](Eigen::Index p) { decode_row(p, out.row(p)); });
  return out;
}

void CompressedTransfer::validate(Eigen::Index vertex_count, bool finite) const {
  // Each array by its name (as Python's prt.CompressedTransfer names it) and shape.
  const auto shape = [](Eigen::Index rows, Eigen::Index cols) {
    return std::to_string(rows) + " x " + std::to_string(cols);
  };
  const auto refuse = [](const std::string& what) {
    throw Error("compressed transfer has inconsistent sizes: " + what);
  };
  if (vertices() != vertex_count)
    refuse("cluster_of_vertex has " + std::to_string(vertices()) + " entries for " +
           std::to_string(vertex_count) + " vertices");
  if (weights.rows() != vertices() || weights.cols() != components)
    refuse("weights is " + shape(weights.rows(), weights.cols()) + ", expected " +
           shape(vertices(), components) + " (vertices x components)");
  if (means.cols() != dimension)
    refuse("means is " + shape(means.rows(), means.cols()) + ", expected clusters x " +
           std::to_string(dimension) + " (the dimension)");
  if (static_cast<Eigen::Index>(representatives.size()) != clusters())
    refuse("representatives has " + std::to_string(representatives.size()) + " blocks for " +
           std::to_string(clusters()) + " clusters (rows of means)");
  for (std::size_t k = 0; k < representatives.size(); ++k) {
    const MatrixXfRow& r = representatives[k];
    if (r.rows() > components || r.cols() != dimension)
      throw Error(
          "compressed transfer has a representative block of the wrong size: "
          "representatives[" +
          std::to_string(k) + "] is " + shape(r.rows(), r.cols()) + ", expected at most " +
          std::to_string(components) + " x " + std::to_string(dimension) +
          " (components x dimension)");
  }
  for (auto k : cluster_of_vertex)
    if (k < 0 || k >= clusters()) throw Error("compressed transfer: cluster index out of range");
  if (!supercluster_of_cluster.empty() &&
      static_cast<Eigen::Index>(supercluster_of_cluster.size()) != clusters())
    throw Error("compressed transfer: supercluster ids do not match the clusters");
  for (auto s : supercluster_of_cluster)
    if (s < 0 || s >= clusters())
      throw Error("compressed transfer: supercluster id " + std::to_string(s) +
                  " out of range (there are " + std::to_string(clusters()) + " clusters)");
  if (finite && !weights.allFinite()) throw Error("compressed transfer: NaN or infinite weight");
  if (finite && !means.allFinite())
    throw Error("compressed transfer: NaN or infinite cluster mean");
  for (const auto& r : representatives)
    if (finite && !r.allFinite())
      throw Error("compressed transfer: NaN or infinite representative");
  if (sparse()) {
    if (static_cast<Eigen::Index>(weight_index.size()) != vertices() * components)
      throw Error("compressed transfer: sparse indices do not match the weights");
    for (auto i : weight_index)
      if (i < 0 || i >= dimension) throw Error("compressed transfer: sparse index out of range");
  }
}

Eigen::Index TransferSignal::vertices() const {
  return file ? file->rows() : coefficients.rows();
}

Eigen::Index TransferSignal::dimension() const {
  return file ? file->cols() : coefficients.cols();
}

Eigen::Map<const MatrixXfRow> TransferSignal::rows() const {
  if (file) return file->matrix();
  return {coefficients.data(), coefficients.rows(), coefficients.cols()};
}

void TransferSignal::release(Eigen::Index first, Eigen::Index last) const {
  if (file) file->release(first, last);
}

TransferSignal TransferSignal::loaded() const {
  TransferSignal out = *this;
  if (!file) return out;
  out.file.reset();
  out.coefficients = rows();
  file->release_all();
  return out;
}

CompressedTransfer exact_form(const TransferSignal& t) {
  // One cluster per vertex whose mean is that vertex's transfer and no
  // components: exact, v x n floats (no n x n identity, which glossy matrices
  // of a large light basis would make gigabytes), relit as VQ is.
  const Eigen::Index v = t.vertices();
  CompressedTransfer c;
  c.compressor = "exact";
  c.dimension = t.dimension();
  c.components = 0;
  c.cluster_of_vertex.resize(static_cast<std::size_t>(v));
  std::iota(c.cluster_of_vertex.begin(), c.cluster_of_vertex.end(), 0);
  c.weights = MatrixXfRow(v, 0);
  c.means = t.rows();
  t.release(0, t.vertices());
  c.representatives.assign(static_cast<std::size_t>(v), MatrixXfRow(0, t.dimension()));
  return c;
}

double CompressedTransfer::stored_floats() const {
  // Sparse: a value and a 32-bit index per kept term, plus the mean.
  if (sparse()) return 2.0 * vertices() * components + double(dimension);
  double floats = 0;
  for (auto k : cluster_of_vertex) floats += components_of(k);
  for (Eigen::Index k = 0; k < clusters(); ++k) floats += double(components_of(k) + 1) * dimension;
  return floats;
}

double squared_error(const MatrixXfRow& exact, const MatrixXfRow& approximation) {
  if (exact.rows() != approximation.rows() || exact.cols() != approximation.cols())
    throw Error("squared_error: shapes differ");
  return (exact.cast<double>() - approximation.cast<double>()).squaredNorm();
}

}  // namespace prt
