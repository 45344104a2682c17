// Cost of one sphere-sphere contact evaluation (narrow phase + law), per law.

#include "contact/contact_law.hpp"

#include <benchmark/benchmark.h>
#include <random>
#include <vector>

namespace {

using kiln::Vec3;
using namespace kiln::contact;

std::vector<ContactInput> inputs(std::size_t n) {
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::vector<ContactInput> v(n);
    for (auto& c : v) {
        c.n = Vec3(u(rng), u(rng), u(rng)).normalized();
        c.overlap = 1e-6 * (1.5 + u(rng));
        c.r_eff = 1e-3;
        c.m_eff = 4e-5;
        c.lever_i = 2e-3;
        c.lever_j = 2e-3;
        c.v_rel = Vec3(u(rng), u(rng), u(rng));
        c.omega_i = Vec3(u(rng), u(rng), u(rng));
        c.omega_j = Vec3(u(rng), u(rng), u(rng));
    }
    return v;
}

template <class Law> void contact_law(benchmark::State& state, Law law) {
    const kiln::Material m{"m", 5e6, 0.45, 2500, 0.3, 0.5, 0.0};
    const kiln::PairProperties p = kiln::PairTable({m}, {}).at(0, 0);
    const auto in = inputs(4096);
    std::vector<Vec3> shear(in.size(), Vec3::Zero());
    const ContactModel model;
    for (auto _ : state) {
        Vec3 sum = Vec3::Zero();
        for (std::size_t k = 0; k < in.size(); ++k) {
            sum += evaluate(law, model, p, in[k], shear[k], 1e-5).force;
        }
        benchmark::DoNotOptimize(sum);
    }
    state.SetItemsProcessed(state.iterations() * static_cast<long>(in.size()));
}

/// The path the pair loop takes: blocks of 16 contacts in structure-of-arrays form, evaluated in an
/// `omp simd` loop (gather and scatter excluded).
template <class Law> void contact_block(benchmark::State& state, Law law) {
    constexpr std::size_t block = 16;
    const kiln::Material m{"m", 5e6, 0.45, 2500, 0.3, 0.5, 0.0};
    const kiln::PairProperties p = kiln::PairTable({m}, {}).at(0, 0);
    const auto in = inputs(4096);
    std::vector<ContactBlock<block>> blocks(in.size() / block);
    for (std::size_t k = 0; k < in.size(); ++k) {
        ContactBlock<block>& c = blocks[k / block];
        const std::size_t b = k % block;
        for (int a = 0; a < 3; ++a) {
            c.n[a][b] = in[k].n[a];
            c.v[a][b] = in[k].v_rel[a];
            c.wi[a][b] = in[k].omega_i[a];
            c.wj[a][b] = in[k].omega_j[a];
            c.s[a][b] = 0.0;
        }
        c.overlap[b] = in[k].overlap;
        c.r_eff[b] = in[k].r_eff;
        c.m_eff[b] = in[k].m_eff;
        c.lever_i[b] = in[k].lever_i;
        c.lever_j[b] = in[k].lever_j;
        c.set_pair(b, p);
    }
    const ContactModel model;
    const double floor = floor_of(model);
    const double rolling = rolling_of(model);
    for (auto _ : state) {
        for (auto& c : blocks) {
#pragma omp simd
            for (std::size_t b = 0; b < block; ++b) {
                evaluate_block(law, floor, rolling, c, b, 1e-5);
            }
            benchmark::DoNotOptimize(c.f[0][0]);
        }
    }
    state.SetItemsProcessed(state.iterations() * static_cast<long>(in.size()));
}

void BM_HertzMindlinBlock(benchmark::State& s) {
    contact_block(s, HertzMindlin{});
}
BENCHMARK(BM_HertzMindlinBlock);

void BM_HertzMindlin(benchmark::State& s) {
    contact_law(s, HertzMindlin{});
}
void BM_LinearSpringDashpot(benchmark::State& s) {
    contact_law(s, LinearSpringDashpot{1e4, 2.0 / 7.0});
}
BENCHMARK(BM_HertzMindlin);
BENCHMARK(BM_LinearSpringDashpot);

} // namespace
