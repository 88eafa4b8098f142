// Parallel building blocks for work inside a pass (they run on the render
// loop's threads and respect its thread count).
#pragma once
#include <tbb/parallel_sort.h>

namespace gradus {

// Sorts [begin, end) in parallel; with a total order (ties broken by an index)
// the result does not depend on the thread count.
template <typename It>
void ParallelSort(It begin, It end) {
    tbb::parallel_sort(begin, end);
}

}  // namespace gradus
