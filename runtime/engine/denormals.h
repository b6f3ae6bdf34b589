// Flush-to-zero and denormals-are-zero for the scope of one inference.
//
// Softmax tails and activation tails produce values below 1.2e-38; on x86 an
// FMA that reads or writes such a denormal takes a microcode assist costing
// around a hundred cycles. Values that small change no pose, so inference runs
// with FTZ/DAZ set (x86 MXCSR bits 15 and 6; aarch64 FPCR.FZ) and the caller's
// mode is restored afterwards. Worker threads set it once at start.
#pragma once

#include <cstdint>

#if defined(__x86_64__) || defined(__i386__)
#include <xmmintrin.h>
#endif

namespace aprt {

class DenormalsAreZero {
 public:
  DenormalsAreZero() noexcept {
#if defined(__x86_64__) || defined(__i386__)
    saved_ = _mm_getcsr();
    _mm_setcsr(saved_ | 0x8040u);
#elif defined(__aarch64__)
    uint64_t fpcr;
    asm volatile("mrs %0, fpcr" : "=r"(fpcr));
    saved_ = fpcr;
    asm volatile("msr fpcr, %0" : : "r"(fpcr | (uint64_t(1) << 24)));
#endif
  }
  ~DenormalsAreZero() {
#if defined(__x86_64__) || defined(__i386__)
    _mm_setcsr(static_cast<unsigned>(saved_));
#elif defined(__aarch64__)
    asm volatile("msr fpcr, %0" : : "r"(saved_));
#endif
  }
  DenormalsAreZero(const DenormalsAreZero&) = delete;
  DenormalsAreZero& operator=(const DenormalsAreZero&) = delete;

 private:
  uint64_t saved_ = 0;
};

}  // namespace aprt
