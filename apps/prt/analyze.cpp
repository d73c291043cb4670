// prt analyze hemisphere: conditioning of the hemispherical Gram matrix and
// the errors of the hemispherical projections of Sloan et al. 2003, §9.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>

#include "commands.hpp"
#include "prt/hemisphere.hpp"
#include "prt/sh.hpp"

namespace prt::cli {

namespace {

std::string band(int index) {
  const int l = static_cast<int>(std::floor(std::sqrt(double(index))));
  return "l=" + std::to_string(l) + ", m=" + std::to_string(index - l * (l + 1));
}

std::string number(double x) {
  char text[40];
  std::snprintf(text, sizeof text, "%.6g", x);
  return text;
}

struct Row {
  std::string method;
  int reflection_order;
  hemisphere::ErrorSummary error;
};

// What both reports print: the Gram matrix's least squares, its most
// redundant function (and the least squares without it), and each
// projection's error.
struct Analysis {
  hemisphere::LeastSquares ls, reduced;
  Eigen::VectorXd residuals;
  std::vector<int> by_residual;  // functions, most redundant first
  std::vector<Row> rows;
};

Analysis analyse(const AnalyzeArgs& args) {
  const int order = args.order;
  Analysis a;
  a.ls = hemisphere::least_squares(order, args.cutoff);
  a.residuals = hemisphere::redundancy_residuals(a.ls.gram);
  a.by_residual.resize(std::size_t(a.residuals.size()));
  for (int i = 0; i < a.residuals.size(); ++i) a.by_residual[std::size_t(i)] = i;
  std::sort(a.by_residual.begin(), a.by_residual.end(),
            [&](int x, int y) { return a.residuals[x] < a.residuals[y]; });
  a.reduced = hemisphere::least_squares(order, args.cutoff, a.by_residual[0]);
  a.rows.push_back(
      {"zero-hemisphere", order, hemisphere::summarize(hemisphere::zero_hemisphere_error(order))});
  a.rows.push_back({"least-squares", order,
                    hemisphere::summarize(hemisphere::least_squares_error(order, a.ls))});
  a.rows.push_back({"least-squares-reduced", order,
                    hemisphere::summarize(hemisphere::least_squares_error(order, a.reduced))});
  for (int m : args.odd_orders)
    a.rows.push_back(
        {"odd-reflection", m, hemisphere::summarize(hemisphere::reflection_error(order, m, true))});
  for (int m : args.even_orders)
    a.rows.push_back({"even-reflection", m,
                      hemisphere::summarize(hemisphere::reflection_error(order, m, false))});
  return a;
}

void print_json(const AnalyzeArgs& args, const Analysis& a) {
  const int order = args.order;
  const Eigen::VectorXd& s = a.ls.singular_values;
  const int redundant = a.by_residual[0];
  std::ostringstream o;
  o << "{\"order\": " << order << ", \"functions\": " << order * order
    << ", \"cutoff\": " << number(args.cutoff) << ",\n \"singular_values\": [";
  for (int i = 0; i < s.size(); ++i) o << (i ? ", " : "") << number(s[i]);
  o << "],\n \"largest_singular_value\": " << number(s[0])
    << ", \"smallest_singular_value\": " << number(s[s.size() - 1])
    << ", \"second_smallest_singular_value\": " << number(s.size() > 1 ? s[s.size() - 2] : 0)
    << ", \"condition_number\": " << number(s[0] / s[s.size() - 1])
    << ", \"discarded_by_cutoff\": " << a.ls.discarded
    << ",\n \"most_redundant\": {\"index\": " << redundant << ", \"band\": \"" << band(redundant)
    << "\", \"residual\": " << number(a.residuals[redundant]) << "}, \"next_redundant\": [";
  for (int i = 1; i < std::min<int>(3, a.residuals.size()); ++i)
    o << (i > 1 ? ", " : "") << "{\"band\": \"" << band(a.by_residual[i])
      << "\", \"residual\": " << number(a.residuals[a.by_residual[i]]) << "}";
  o << "],\n \"reduced_basis_functions\": " << a.reduced.kept.size()
    << ", \"reduced_smallest_singular_value\": " << number(a.reduced.singular_values.minCoeff())
    << ",\n \"errors\": [";
  for (std::size_t i = 0; i < a.rows.size(); ++i)
    o << (i ? ",\n   " : "\n   ") << "{\"method\": \"" << a.rows[i].method
      << "\", \"reflection_order\": " << a.rows[i].reflection_order
      << ", \"worst_squared_error\": " << number(a.rows[i].error.worst)
      << ", \"average_squared_error\": " << number(a.rows[i].error.average)
      << ", \"worst_rms\": " << number(std::sqrt(std::max(0.0, a.rows[i].error.worst)))
      << ", \"average_rms\": " << number(std::sqrt(std::max(0.0, a.rows[i].error.average))) << "}";
  o << "]}\n";
  std::cout << o.str();
}

void print_text(const AnalyzeArgs& args, const Analysis& a) {
  const int order = args.order;
  const Eigen::VectorXd& s = a.ls.singular_values;
  const int redundant = a.by_residual[0];
  std::printf("hemispherical SH, order %d (%d functions), Gram matrix A_ik = int_H y_i y_k\n",
              order, order * order);
  std::printf(
      "singular values of A: largest %.6g, smallest %.6g, second smallest %.6g, "
      "condition %.4g\n",
      s[0], s[s.size() - 1], s.size() > 1 ? s[s.size() - 2] : 0.0, s[0] / s[s.size() - 1]);
  std::printf("most redundant: %s (index %d), residual %.4g; next %s %.4g, %s %.4g\n",
              band(redundant).c_str(), redundant, a.residuals[redundant],
              band(a.by_residual[1]).c_str(), a.residuals[a.by_residual[1]],
              band(a.by_residual[2]).c_str(), a.residuals[a.by_residual[2]]);
  std::printf(
      "least squares: cut-off %.3g x largest, %d singular value(s) discarded; reduced "
      "basis of %zu functions: smallest singular value %.4g\n",
      args.cutoff, a.ls.discarded, a.reduced.kept.size(), a.reduced.singular_values.minCoeff());
  std::printf("\nsquared error over H of unit-power signals of the order-%d space:\n", order);
  std::printf("%-24s %6s %12s %12s %10s %10s\n", "projection", "order", "worst", "average",
              "worst RMS", "avg RMS");
  for (const auto& r : a.rows)
    std::printf("%-24s %6d %12.6g %12.6g %9.1f%% %9.1f%%\n", r.method.c_str(), r.reflection_order,
                r.error.worst, r.error.average, 100 * std::sqrt(std::max(0.0, r.error.worst)),
                100 * std::sqrt(std::max(0.0, r.error.average)));
}

}  // namespace

int analyze_hemisphere(const AnalyzeArgs& args) {
  const Analysis analysis = analyse(args);
  if (args.json)
    print_json(args, analysis);
  else
    print_text(args, analysis);
  return 0;
}

}  // namespace prt::cli
