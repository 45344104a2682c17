#pragma once
// Orientation convention and the rotation integrator of torque-driven rigid bodies.
//
// Convention (used everywhere in kiln):
// - The orientation of a particle is a unit quaternion q = (w, x, y, z), Eigen::Quaterniond,
//   stored in memory as (x, y, z, w) (Eigen's coeffs() order). It rotates BODY-frame vectors into
//   the WORLD frame: v_world = q * v_body * conj(q) = R(q) v_body. The columns of R(q) are the body
//   axes written in the world frame.
// - The body frame of every shape template is its principal frame with the origin at the centre of
//   mass, so the inertia tensor in the body frame is diag(I1, I2, I3).
// - The state of a rotating body is (q, L), L the angular momentum in the WORLD frame
//   (kg m^2/s). The angular velocity is derived: omega_world = R diag(1/I) R^T L.
//
// Integrator: symmetric splitting of the free rigid body (Dullweber, Leimkuhler & McLachlan 1997,
// J. Chem. Phys. 107, 5840, Sec. III; the quaternion form is NO_SQUISH, Miller et al. 2002,
// J. Chem. Phys. 116, 8649, Eqs. 17-24), wrapped in the same half-kick / drift / half-kick as the
// translational velocity Verlet:
//   L += dt/2 tau_world;  q <- free_rotate(q, L, I, dt);  (new torque);  L += dt/2 tau_world.
// The free rotation is the composition of exact rotations about single principal axes,
//   X(dt/2) Y(dt/2) Z(dt) Y(dt/2) X(dt/2),
// each of which is the exact flow of T_k = L_k^2/(2 I_k). Hence: L_world is untouched by the free
// step (|L| exact to round-off), the map is symplectic and time-reversible (energy error bounded,
// O(dt^2), no drift), and the scheme is second order. The seed thesis' Munjiza scheme (Eqs. 15-21
// of Oschmann 2019) rotates with a constant angular velocity over the step, which is first order
// in the gyroscopic term and does not keep the energy bounded over long runs.
//
// Spheres do not need any of this: for a sphere L = I omega in every frame.

#include "core/types.hpp"

#include <cmath>
#include <cstddef>
#include <cstdint>

namespace kiln::geometry {

/// Rotation matrix R(q) of a quaternion (normalised first); maps body-frame vectors to world.
[[nodiscard]] Mat3 rotation_matrix(const Quat& q);

/// Rotation matrix R(q) of a quaternion already of unit norm (not normalised again; body -> world).
/// Standard form (e.g. Shoemake 1985) with w the scalar part. Inline: called once per body and
/// step, an out-of-line call returned the matrix through the stack, and the caller's wide copy of
/// it into the store waited on the callee's narrow stores (about half of `rotate_bodies`).
[[nodiscard]] inline Mat3 unit_rotation_matrix(const Quat& u) {
    const double w = u.w();
    const double x = u.x();
    const double y = u.y();
    const double z = u.z();
    Mat3 r;
    r << 1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y), //
        2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),  //
        2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y);
    return r;
}

/// World-frame vector of a body-frame vector v_body under orientation q (body -> world).
[[nodiscard]] inline Vec3 body_to_world(const Quat& q, const Vec3& v_body) {
    return q * v_body;
}

/// Body-frame vector of a world-frame vector v_world under orientation q (body -> world).
[[nodiscard]] inline Vec3 world_to_body(const Quat& q, const Vec3& v_world) {
    return q.conjugate() * v_world;
}

/// Angular velocity in the world frame (rad/s) from world angular momentum L (kg m^2/s),
/// orientation q (body -> world) and principal moments I (kg m^2, body frame).
[[nodiscard]] Vec3 angular_velocity_world(const Quat& q, const Vec3& L_world,
                                          const Vec3& inertia_principal);

/// World angular momentum (kg m^2/s) from a world angular velocity (rad/s).
[[nodiscard]] Vec3 angular_momentum_world(const Quat& q, const Vec3& omega_world,
                                          const Vec3& inertia_principal);

/// Rotational kinetic energy (J) = sum_k L_k^2 / (2 I_k), L in the body frame.
[[nodiscard]] double rotational_energy(const Quat& q, const Vec3& L_world,
                                       const Vec3& inertia_principal);

/// Half kick (or any kick): L_world += dt * torque_world (N m, s).
inline void kick_angular_momentum(Vec3& L_world, const Vec3& torque_world, double dt) {
    L_world += dt * torque_world;
}

/// Relative spread of the principal moments below which a body is a spherical top (cube,
/// regular polyhedron: moments equal but for the round-off of their computation).
inline constexpr double kSphericalTop = 1e-12;
/// Whether the principal moments (kg m^2) are those of a spherical top (kSphericalTop).
[[nodiscard]] inline bool spherical_top(const Vec3& inertia_principal) {
    return inertia_principal.maxCoeff() - inertia_principal.minCoeff() <=
           kSphericalTop * inertia_principal.maxCoeff();
}
/// The one moment (kg m^2) a spherical top is given: the mean of its three.
[[nodiscard]] inline double spherical_moment(const Vec3& inertia_principal) {
    return inertia_principal.sum() / 3.0;
}

/// The symmetry axis of a symmetric top: the body axis (0, 1, 2) whose moment differs while the
/// other two are equal to a relative kSphericalTop (cuboids of square section, regular prisms,
/// square pyramids, rotationally symmetric clumps and superquadrics); -1 for a spherical top or
/// three different moments (kg m^2, body frame).
[[nodiscard]] inline int symmetric_axis(const Vec3& inertia_principal) {
    if (spherical_top(inertia_principal)) {
        return -1;
    }
    const double tol = kSphericalTop * inertia_principal.maxCoeff();
    for (int s = 0; s < 3; ++s) {
        const double a = inertia_principal[(s + 1) % 3];
        const double b = inertia_principal[(s + 2) % 3];
        if (std::abs(a - b) <= tol) {
            return s;
        }
    }
    return -1;
}
/// The moment (kg m^2) about the axes across the symmetry axis s of a symmetric top: the mean of
/// the two equal ones.
[[nodiscard]] inline double transverse_moment(const Vec3& inertia_principal, int s) {
    return 0.5 * (inertia_principal[(s + 1) % 3] + inertia_principal[(s + 2) % 3]);
}

/// Torque-free rotation over dt (s) by the symmetric splitting X(dt/2) Y(dt/2) Z(dt) Y(dt/2)
/// X(dt/2) (Dullweber et al. 1997). Updates q (body -> world, renormalised); L_world is constant
/// under free rotation and is therefore not an argument to modify. Inertia in the body frame
/// (kg m^2, all > 0). A spherical top (spherical_top) instead turns exactly: about the fixed L at
/// omega = L / spherical_moment(I), which the splitting only approximates (its sub-rotations do
/// not commute; error O((omega dt)^3) per step). So does a symmetric top (symmetric_axis >= 0):
/// about L at |L| / i_p composed with a spin about its symmetry axis (docs/theory/rotation.md).
void free_rotate(Quat& q, const Vec3& L_world, const Vec3& inertia_principal, double dt);

/// As above for a body whose rotation matrix is kept alongside q: `rot` is R(q) (body -> world)
/// on entry and unit_rotation_matrix of the new (normalised) q on exit. The same splitting, with
/// each single-axis factor applied component by component and the sine and cosine of small
/// angles from a series accurate to round-off (no library call in the usual case): the form the
/// step loop uses for every body.
void free_rotate(Quat& q, Mat3& rot, const Vec3& L_world, const Vec3& inertia_principal, double dt);

/// free_rotate for the bodies index[0 .. n) of particle arrays: q (body -> world, updated and
/// renormalised), rot = R(q) on entry (not updated: take unit_rotation_matrix of the new q), world
/// angular momenta (kg m^2/s) and principal moments (kg m^2, body frame). Bodies are turned eight
/// at a time in vector lanes, spherical tops, symmetric tops and the others in batches of their
/// own; the same flows, splitting and series as free_rotate, a body turning faster than the
/// series allows taking the general path.
void free_rotate_bodies(const std::uint32_t* index, std::size_t n, Quat* q, const Mat3* rot,
                        const Vec3* L_world, const Vec3* inertia_principal, double dt);

/// Angular velocity (rad/s, world frame) of a symmetric top with symmetry axis s (symmetric_axis)
/// along the world unit vector e (R e_s): L / i_p + (1 / i_s - 1 / i_p) (L . e) e, which is
/// R diag(1/I) R^T L for I = (i_p, i_p, i_s) without the two products by R.
[[nodiscard]] inline Vec3 symmetric_omega(const Vec3& e, const Vec3& L_world,
                                          const Vec3& inertia_principal, int s) {
    const double inv_p = 1.0 / transverse_moment(inertia_principal, s);
    const double inv_s = 1.0 / inertia_principal[s];
    return inv_p * L_world + ((inv_s - inv_p) * e.dot(L_world)) * e;
}

/// Angular velocity in the world frame (rad/s) from rot = R(q) (body -> world), the world angular
/// momentum (kg m^2/s) and the principal moments (kg m^2, body frame): R diag(1/I) R^T L.
[[nodiscard]] inline Vec3 angular_velocity_world(const Mat3& rot, const Vec3& L_world,
                                                 const Vec3& inertia_principal) {
    if (spherical_top(inertia_principal)) {
        return L_world * (3.0 / inertia_principal.sum()); // L / spherical_moment, one division
    }
    if (const int s = symmetric_axis(inertia_principal); s >= 0) {
        return symmetric_omega(rot.col(s), L_world, inertia_principal, s);
    }
    const Vec3 l_body = rot.transpose() * L_world;
    return rot * l_body.cwiseQuotient(inertia_principal);
}

/// One full velocity-Verlet rotation step with a constant torque over the step (used by tests and
/// validation; System will call kick / free_rotate / kick around its force computation).
void rotation_step(Quat& q, Vec3& L_world, const Vec3& inertia_principal, const Vec3& torque_world,
                   double dt);

/// Complete elliptic integral of the first kind K(m), parameter m = k^2 in [0, 1), by the
/// arithmetic-geometric mean (Abramowitz & Stegun 17.6).
[[nodiscard]] double elliptic_k(double m);

/// Analytic time between two successive sign changes of the intermediate-axis body angular
/// velocity of a torque-free rigid body (s): 2 K(m) / s_rate from the Jacobi elliptic solution
/// (Landau & Lifshitz, Mechanics, Sec. 37, Eqs. 37.10-37.12). I in the body frame, ordered
/// I1 < I2 < I3; L2 = |L|^2 (kg^2 m^4/s^2), energy E (J); requires 2 E I1 < L2 < 2 E I3 and
/// L2 != 2 E I2 (not the separatrix).
[[nodiscard]] double free_rotor_half_period(const Vec3& inertia_sorted, double L2, double energy);

} // namespace kiln::geometry
