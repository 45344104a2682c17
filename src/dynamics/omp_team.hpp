#pragma once
// Internal to src/dynamics: how the steps' loops meet OpenMP.

#ifdef _OPENMP
#include <omp.h>
#endif

namespace kiln::dynamics::detail {

/// Runs f, whose loops are orphaned `omp for` constructs, in a team of `threads` threads, or
/// directly when there is one thread and no enclosing parallel region: there libgomp forms no
/// team and the loops' implicit barriers return at once, while a team of one thread still ends
/// each barrier with a system call waking its (absent) waiters, 0.6 us each on a virtual machine
/// (docs/performance.md, "Session 28"). The same iterations in the same order either way, so the
/// same bits. A region that should run in parallel only with enough work passes `threads = 1`
/// otherwise (the form of `#pragma omp parallel ... if (cond)`, without its team of one).
template <class F> void in_team(int threads, F&& f) {
#ifdef _OPENMP
    if (threads == 1 && !omp_in_parallel()) {
        f();
        return;
    }
#endif
#pragma omp parallel num_threads(threads)
    f();
}

} // namespace kiln::dynamics::detail
