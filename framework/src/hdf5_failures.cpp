#include "hdf5_failures.hpp"

#include <cstdlib>

#include "child_process.hpp"
#include "prt/output_file.hpp"

namespace prt {

Hdf5FailureRecorder::Hdf5FailureRecorder(std::filesystem::path file) : file_(std::move(file)) {
  H5Eget_auto2(H5E_DEFAULT, &previous_function_, &previous_data_);
  H5Eset_auto2(H5E_DEFAULT, &Hdf5FailureRecorder::record, this);
}

Hdf5FailureRecorder::~Hdf5FailureRecorder() {
  H5Eset_auto2(H5E_DEFAULT, previous_function_, previous_data_);
}

herr_t Hdf5FailureRecorder::record(hid_t stack, void* self) {
  auto* recorder = static_cast<Hdf5FailureRecorder*>(self);
  if (!recorder->failed_) {
    recorder->failed_ = true;
    H5Ewalk2(stack, H5E_WALK_UPWARD, &Hdf5FailureRecorder::walk, recorder);
    if (in_child_process()) fail_child_process(recorder->message());
  }
  return 0;
}

// Upward: the innermost entry first. The sec2 driver's write failure reads
// "file write failed: ..., errno = 28, error message = '...', ...".
herr_t Hdf5FailureRecorder::walk(unsigned depth, const H5E_error2_t* entry, void* self) {
  auto* recorder = static_cast<Hdf5FailureRecorder*>(self);
  const std::string description = entry->desc ? entry->desc : "";
  if (depth == 0) recorder->innermost_ = description;
  const auto at = description.find("errno = ");
  if (recorder->error_number_ == 0 && at != std::string::npos)
    recorder->error_number_ = std::atoi(description.c_str() + at + 8);
  return 0;
}

std::string Hdf5FailureRecorder::message(const std::string& detail) const {
  if (error_number_ > 0) return io_failure(file_, error_number_, "writing");
  const std::string why = !innermost_.empty() ? innermost_ : detail;
  return file_.string() + ": cannot write the bake file" + (why.empty() ? "" : ": " + why);
}

}  // namespace prt
