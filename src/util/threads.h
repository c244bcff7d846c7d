#pragma once

// The OpenMP team as the code that shares work by hand sees it: how many
// threads a parallel region gets and which one runs. Without OpenMP, one.
// Header only: each file answers with its own compile flags.

#include <algorithm>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace mr {

// The threads of the next parallel region (at least 1).
inline int NumThreads() {
#ifdef _OPENMP
  return std::max(1, omp_get_max_threads());
#else
  return 1;
#endif
}

// The calling thread's index within its parallel region (0 outside one).
inline int ThreadIndex() {
#ifdef _OPENMP
  return omp_get_thread_num();
#else
  return 0;
#endif
}

}  // namespace mr
