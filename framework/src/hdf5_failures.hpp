// Failures of libhdf5 calls while a file is written. The C++ wrappers throw
// where a call returns an error, but their destructors only print (a
// dataset's flush on close is where a full disk shows): this records every
// failure on the writing thread, with the system's reason when the file
// driver gives one, so that the writer refuses to keep the file.
#pragma once
#include <H5Epublic.h>

#include <filesystem>
#include <string>

namespace prt {

class Hdf5FailureRecorder {
 public:
  // `file`: the name messages give. In a child of run_in_child_process the
  // first failure ends the child there, with the message, so that no later
  // call (a close after a failed flush double-frees in libhdf5 1.10) runs.
  explicit Hdf5FailureRecorder(std::filesystem::path file);
  ~Hdf5FailureRecorder();
  Hdf5FailureRecorder(const Hdf5FailureRecorder&) = delete;
  Hdf5FailureRecorder& operator=(const Hdf5FailureRecorder&) = delete;

  bool failed() const { return failed_; }
  // "FILE: no space left on device while writing" where the driver gave an
  // errno, otherwise "FILE: cannot write the bake file: DETAIL".
  std::string message(const std::string& detail = "") const;

 private:
  static herr_t record(hid_t stack, void* self);
  static herr_t walk(unsigned depth, const H5E_error2_t* entry, void* self);

  std::filesystem::path file_;
  H5E_auto2_t previous_function_ = nullptr;
  void* previous_data_ = nullptr;
  bool failed_ = false;
  int error_number_ = 0;   // the driver's errno, 0 when none was given
  std::string innermost_;  // the deepest entry's description
};

}  // namespace prt
