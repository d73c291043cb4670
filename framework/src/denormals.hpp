// Flush-to-zero and denormals-are-zero for the scope of a trace: Embree's
// traversal then never takes the slow path of denormal arithmetic (Embree's
// own advice). The thread's previous mode is restored on exit, so the
// double-precision projection that follows on the same thread is unchanged.
#pragma once
#if defined(__SSE2__)
#include <pmmintrin.h>
#include <xmmintrin.h>
#endif

namespace prt {

#if defined(__SSE2__)
class FlushDenormals {
 public:
  FlushDenormals() : saved_(_mm_getcsr()) {
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
  }
  ~FlushDenormals() { _mm_setcsr(saved_); }
  FlushDenormals(const FlushDenormals&) = delete;
  FlushDenormals& operator=(const FlushDenormals&) = delete;

 private:
  unsigned saved_;
};
#else
struct FlushDenormals {};  // elsewhere the trace keeps the thread's mode
#endif

}  // namespace prt
