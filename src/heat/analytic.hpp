#pragma once
// Classical series solutions of transient conduction with convection to a fluid at T_inf from a
// uniform initial temperature T_0 (Carslaw & Jaeger 1959, Conduction of Heat in Solids, §3.11
// slab and §9.4 sphere; also Incropera et al., Fundamentals of Heat and Mass Transfer, 6th ed.,
// eqs. 5.39-5.40 slab and 5.50-5.51 sphere). All return theta = (T - T_inf) / (T_0 - T_inf).

#include <vector>

namespace kiln::heat::analytic {

/// First `count` positive roots of lambda cot(lambda) = 1 - Bi (sphere, Bi = h R / k > 0), one in
/// each interval ((n-1) pi, n pi), found by bisection to machine precision.
[[nodiscard]] std::vector<double> sphere_eigenvalues(double biot, int count);

/// First `count` positive roots of lambda tan(lambda) = Bi (slab, Bi = h L / k > 0, L the half
/// thickness), one in each interval ((n-1) pi, (n - 1/2) pi).
[[nodiscard]] std::vector<double> slab_eigenvalues(double biot, int count);

/// Sphere: theta at radius fraction r/R in [0, 1] and Fourier number Fo = alpha t / R^2.
[[nodiscard]] double sphere_theta(const std::vector<double>& lambda, double r_over_r, double fo);

/// Sphere: volume-mean theta at Fo.
[[nodiscard]] double sphere_mean_theta(const std::vector<double>& lambda, double fo);

/// Slab: theta at x/L in [-1, 1] and Fo = alpha t / L^2.
[[nodiscard]] double slab_theta(const std::vector<double>& lambda, double x_over_l, double fo);

/// Slab: mean theta over the thickness at Fo.
[[nodiscard]] double slab_mean_theta(const std::vector<double>& lambda, double fo);

} // namespace kiln::heat::analytic
