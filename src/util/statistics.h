#pragma once

// Order statistics of a sample (medians, quantiles) by selection rather than
// sorting: std::nth_element is O(n), and these run over every pixel or vertex
// of a view. All of them pick an element of the sample (no interpolation
// between neighbours), so the result is one of the inputs, bit for bit.

#include <algorithm>
#include <cstddef>
#include <vector>

#include "util/error.h"

namespace mr {

// The element of 0-based rank `k` of `values`: what (*values)[k] would be once
// sorted ascending. Reorders `values` (partially) to find it.
template <typename T>
T NthSmallest(std::vector<T>* values, size_t k) {
  MR_CHECK_LT(k, values->size());
  std::nth_element(values->begin(), values->begin() + k, values->end());
  return (*values)[k];
}

// The rank floor(q * n), clamped to n - 1 so that q = 1 names the largest of
// n > 0 elements. q is in [0, 1].
inline size_t QuantileRank(size_t n, double q) {
  MR_CHECK(n > 0);
  // Also refuses NaN, and a negative q, whose conversion to size_t is undefined.
  MR_CHECK(q >= 0 && q <= 1) << "q = " << q;
  return std::min(n - 1, static_cast<size_t>(q * static_cast<double>(n)));
}

// The q-quantile of `values` as the element of rank floor(q * n) (clamped to
// n - 1): q = 0 is the minimum, q = 0.5 the upper median, q = 1 the maximum.
// Reorders `values`; they must not be empty.
template <typename T>
T Quantile(std::vector<T>* values, double q) {
  return NthSmallest(values, QuantileRank(values->size(), q));
}

// The upper median of `values`, the element of rank n / 2 (for an even n, the
// larger of the two middle elements, not their mean, so that it is one of the
// inputs). Reorders `values`; they must not be empty.
template <typename T>
T Median(std::vector<T>* values) {
  MR_CHECK(!values->empty());
  return NthSmallest(values, values->size() / 2);
}

// A sample's median and its spread as a robust standard deviation: 1.4826 x
// the median absolute deviation from the median, which is the standard
// deviation for normally distributed values and ignores a minority of
// outliers. Reorders `values`, which must not be empty, and leaves them as the
// absolute deviations.
struct MedianAndSpread {
  double median = 0;
  double sigma = 0;
};
inline MedianAndSpread RobustMedianAndSpread(std::vector<double>* values) {
  MedianAndSpread out;
  out.median = Median(values);
  for (double& v : *values) v = v > out.median ? v - out.median : out.median - v;
  out.sigma = 1.4826 * Median(values);
  return out;
}

}  // namespace mr
