// Where an iterative algorithm (a basis fit, LBG, CPCA) keeps its state
// between passes, so that a killed run resumes where it was: named parts,
// each kept whole or not at all. The algorithm sees only this interface; the
// run layer's checkpoint folder (prt/checkpoint.hpp) implements it, and
// decides where the parts live and when they are removed.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "prt/transfer.hpp"

namespace prt {

class PartKeeper {
 public:
  virtual ~PartKeeper() = default;
  virtual bool has(const std::string& name) const = 0;
  virtual void save(const std::string& name, const MatrixXfRow& matrix) const = 0;
  virtual void save(const std::string& name, const Eigen::MatrixXd& matrix) const = 0;
  virtual void save(const std::string& name, const std::vector<std::int32_t>& values) const = 0;
  virtual MatrixXfRow load_floats(const std::string& name) const = 0;
  virtual Eigen::MatrixXd load_doubles(const std::string& name) const = 0;
  virtual std::vector<std::int32_t> load_ints(const std::string& name) const = 0;
  // Deletes a part superseded by a later one.
  virtual void remove_part(const std::string& name) const = 0;
  // Where the parts are, for messages ("kept in ...").
  virtual std::string where() const = 0;
};

}  // namespace prt
