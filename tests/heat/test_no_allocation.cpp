// A thermal step with the iterative solvers must not allocate: global operator new is counted.

#include "heat/cartesian_grid.hpp"
#include "heat/resolved_model.hpp"

#include <atomic>
#include <cstdlib>
#include <gtest/gtest.h>
#include <memory>
#include <new>
#include <vector>

namespace {
std::atomic<long> allocations{0};
}

void* operator new(std::size_t n) {
    allocations.fetch_add(1, std::memory_order_relaxed);
    if (void* p = std::malloc(n == 0 ? 1 : n)) {
        return p;
    }
    throw std::bad_alloc();
}
// The replacement pair is malloc/free by construction; GCC 12 (RelWithDebInfo) misreads the
// replaced operator new inlined here as a mismatch.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void operator delete(void* p) noexcept {
    std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
    std::free(p);
}
#pragma GCC diagnostic pop

namespace kiln::heat {
namespace {

TEST(NoAllocation, IterativeStepsDoNotAllocate) {
    const auto g = std::make_shared<const ThermalGrid>(
        make_cartesian_grid(Superquadric{Vec3(0.01, 0.008, 0.006), 0.5, 0.8}, {.cells_across = 8}));
    const std::vector<double> h{100.0};
    std::vector<double> rate(g->boundary.size(), 1e-3);
    for (const SolverKind k : {SolverKind::cg, SolverKind::bicgstab}) {
        ResolvedOperator op(g, {1.0, 2000.0, 1000.0}, 0.1, h, {k, 1e-10, 1000});
        std::vector<double> t(static_cast<std::size_t>(g->size()), 300.0);
        (void)op.step(t, {.ambient = 400.0, .heat_rate = rate});
        const long before = allocations.load();
        for (int s = 0; s < 10; ++s) {
            (void)op.step(t, {.ambient = 400.0, .heat_rate = rate});
        }
        EXPECT_EQ(allocations.load() - before, 0) << to_string(k);
    }
}

} // namespace
} // namespace kiln::heat
