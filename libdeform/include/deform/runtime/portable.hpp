#pragma once
// The one place for compiler-specific spellings (builtins, attributes, pragmas): everything else in libdeform is
// standard C++20 and compiles with -Wpedantic on GCC and Clang. Each macro has a GCC/Clang form, an MSVC form where
// one exists, and a do-nothing fallback; none changes a result, only how fast it comes.
//
//   DEFORM_ALWAYS_INLINE   a function inlined into every caller (a kernel's block step, so that its vectors stay in
//                          registers); use as `DEFORM_ALWAYS_INLINE inline void f()` or on a member function.
//   DEFORM_NOINLINE        a function kept out of line (a cold set-up step next to a hot loop).
//   DEFORM_UNROLL          the next loop unrolled completely (up to 16 iterations).
//   DEFORM_PREFETCH(address, for_writing)
//                          a cache hint for the line holding `address` (a const void*); for_writing 1 asks for it
//                          for writing (PREFETCHW where the file is compiled with -mprfchw), 0 for reading.
//   DEFORM_X86_CPU_INIT() and DEFORM_X86_CPU_SUPPORTS("feature")
//                          the running CPU's x86 features, for choosing a kernel copy (isa.cpp); where the compiler
//                          has no such query, every feature reads as absent and the portable kernels run.
#if defined(__GNUC__) || defined(__clang__)
#define DEFORM_ALWAYS_INLINE [[gnu::always_inline]]
#define DEFORM_NOINLINE [[gnu::noinline]]
#define DEFORM_UNROLL _Pragma("GCC unroll 16")  // Clang reads it too
#define DEFORM_PREFETCH(address, for_writing) __builtin_prefetch((address), (for_writing), 3)
#if defined(__x86_64__) || defined(__i386__)
#define DEFORM_X86_CPU_INIT() __builtin_cpu_init()
#define DEFORM_X86_CPU_SUPPORTS(feature) (__builtin_cpu_supports(feature) != 0)
#endif
#elif defined(_MSC_VER)
#include <intrin.h>
#define DEFORM_ALWAYS_INLINE [[msvc::forceinline]]
#define DEFORM_NOINLINE [[msvc::noinline]]
#define DEFORM_UNROLL
#if defined(_M_X64) || defined(_M_IX86)
#define DEFORM_PREFETCH(address, for_writing) \
  _mm_prefetch(static_cast<const char*>(static_cast<const void*>(address)), _MM_HINT_T0)
#else
#define DEFORM_PREFETCH(address, for_writing) ((void)(address), (void)(for_writing))
#endif
#else
#define DEFORM_ALWAYS_INLINE
#define DEFORM_NOINLINE
#define DEFORM_UNROLL
#define DEFORM_PREFETCH(address, for_writing) ((void)(address), (void)(for_writing))
#endif
#if !defined(DEFORM_X86_CPU_INIT)
#define DEFORM_X86_CPU_INIT() ((void)0)
#define DEFORM_X86_CPU_SUPPORTS(feature) ((void)(feature), false)
#endif
