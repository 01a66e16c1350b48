// stipple core — narrowing conversions on the fixed-point paths.
//
// Every product the client forms is bounded where it is formed (the ranges
// in docs/fixed_point.md); a narrowing conversion of such a value is written
// `narrow<T>(v)`, which states that the bound holds. Checked builds
// (STIPPLE_CHECK_RANGES=1: the asan preset and the fuzzers) trap when it
// does not, so the extreme-input tests, the hostile-file tests and the
// fuzzers verify each bound rather than trust it; other builds convert
// plainly. A value whose bound depends on the input's data and is not
// proven is clamped where it is formed instead (σ from the file, colour
// offsets, depth words), in every build.
#pragma once

#include <cstdint>
#include <utility>

#ifndef STIPPLE_CHECK_RANGES
#define STIPPLE_CHECK_RANGES 0
#endif

namespace stipple {

template <class To, class From>
constexpr To narrow(From v) {
#if STIPPLE_CHECK_RANGES
  if (!std::in_range<To>(v)) __builtin_trap();  // a bound in docs/fixed_point.md does not hold
#endif
  return static_cast<To>(v);
}

}  // namespace stipple
