// Rotation convention and splitting integrator; see rotation.hpp and docs/theory/rotation.md.

#include "geometry/rotation.hpp"

#include "core/error.hpp"

#include <cmath>
#include <numbers>
#include <utility>

namespace kiln::geometry {

Mat3 rotation_matrix(const Quat& q) {
    // Standard form (e.g. Shoemake 1985) with w the scalar part; the seed's printed matrix
    // (Oschmann 2019, Table 3) has a wrong (2,2) entry and sign errors and is not used.
    return unit_rotation_matrix(q.normalized());
}

Mat3 unit_rotation_matrix(const Quat& u) {
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

Vec3 angular_velocity_world(const Quat& q, const Vec3& L_world, const Vec3& inertia_principal) {
    const Vec3 l_body = world_to_body(q, L_world);
    return body_to_world(q, l_body.cwiseQuotient(inertia_principal));
}

Vec3 angular_momentum_world(const Quat& q, const Vec3& omega_world, const Vec3& inertia_principal) {
    const Vec3 w_body = world_to_body(q, omega_world);
    return body_to_world(q, w_body.cwiseProduct(inertia_principal));
}

double rotational_energy(const Quat& q, const Vec3& L_world, const Vec3& inertia_principal) {
    const Vec3 l_body = world_to_body(q, L_world);
    return 0.5 * l_body.cwiseProduct(l_body).cwiseQuotient(inertia_principal).sum();
}

namespace {

/// Sine and cosine of x (rad). For |x| <= 1/16 (a body turning by less than 1/8 rad per half
/// step, the usual case by far) the Taylor series to x^9 and x^10: the first omitted terms,
/// x^11/11! and x^12/12!, are below 2e-20 relative, far under one unit in the last place; the
/// library otherwise.
void sin_cos(double x, double& s, double& c) {
    if (std::abs(x) <= 0.0625) {
        const double x2 = x * x;
        s = x * (1.0 + x2 * (-1.0 / 6.0 +
                             x2 * (1.0 / 120.0 + x2 * (-1.0 / 5040.0 + x2 * (1.0 / 362880.0)))));
        c = 1.0 +
            x2 * (-0.5 + x2 * (1.0 / 24.0 + x2 * (-1.0 / 720.0 +
                                                  x2 * (1.0 / 40320.0 + x2 * (-1.0 / 3628800.0)))));
        return;
    }
    s = std::sin(x);
    c = std::cos(x);
}

/// Exact flow of T_k = L_k^2 / (2 I_k) over h: the body turns by phi = h L_k / I_k about body axis
/// k, so q <- q * exp(phi/2 e_k) and the body components of L turn by -phi about e_k.
/// One sine and cosine of the half angle serve both: cos phi = ch^2 - sh^2, sin phi = 2 sh ch.
/// The quaternion product with the single-axis factor (ch, sh e_k) is written out: with (i, j, k)
/// cyclic, w' = ch w - sh v_k, v_k' = ch v_k + sh w, v_i' = ch v_i + sh v_j, v_j' = ch v_j - sh
/// v_i.
template <int k> void rotate_about_axis(double qv[4], Vec3& l_body, const Vec3& inertia, double h) {
    const double phi = h * l_body[k] / inertia[k];
    double sh = 0.0;
    double ch = 1.0;
    sin_cos(0.5 * phi, sh, ch);
    const double c = (ch - sh) * (ch + sh);
    const double s = 2.0 * sh * ch;
    constexpr int i = (k + 1) % 3;
    constexpr int j = (k + 2) % 3;
    const double li = l_body[i];
    const double lj = l_body[j];
    l_body[i] = c * li + s * lj;
    l_body[j] = -s * li + c * lj;
    // qv = (x, y, z, w): vector part first, as Eigen stores it.
    const double w = qv[3];
    const double vi = qv[i];
    const double vj = qv[j];
    const double vk = qv[k];
    qv[3] = ch * w - sh * vk;
    qv[k] = ch * vk + sh * w;
    qv[i] = ch * vi + sh * vj;
    qv[j] = ch * vj - sh * vi;
}

} // namespace

void free_rotate(Quat& q, Mat3& rot, const Vec3& L_world, const Vec3& inertia_principal,
                 double dt) {
    KILN_ASSERT((inertia_principal.array() > 0.0).all());
    Vec3 l_body = rot.transpose() * L_world;
    double qv[4] = {q.x(), q.y(), q.z(), q.w()};
    rotate_about_axis<0>(qv, l_body, inertia_principal, 0.5 * dt);
    rotate_about_axis<1>(qv, l_body, inertia_principal, 0.5 * dt);
    rotate_about_axis<2>(qv, l_body, inertia_principal, dt);
    rotate_about_axis<1>(qv, l_body, inertia_principal, 0.5 * dt);
    rotate_about_axis<0>(qv, l_body, inertia_principal, 0.5 * dt);
    q = Quat(qv[3], qv[0], qv[1], qv[2]);
    q.normalize();
    rot = unit_rotation_matrix(q);
}

void free_rotate(Quat& q, const Vec3& L_world, const Vec3& inertia_principal, double dt) {
    Mat3 rot = unit_rotation_matrix(q.normalized());
    free_rotate(q, rot, L_world, inertia_principal, dt);
}

void rotation_step(Quat& q, Vec3& L_world, const Vec3& inertia_principal, const Vec3& torque_world,
                   double dt) {
    kick_angular_momentum(L_world, torque_world, 0.5 * dt);
    free_rotate(q, L_world, inertia_principal, dt);
    kick_angular_momentum(L_world, torque_world, 0.5 * dt);
}

double elliptic_k(double m) {
    KILN_ASSERT(m >= 0.0 && m < 1.0);
    double a = 1.0;
    double b = std::sqrt(1.0 - m);
    for (int it = 0; it < 60 && std::abs(a - b) > 1e-16 * a; ++it) {
        const double an = 0.5 * (a + b);
        b = std::sqrt(a * b);
        a = an;
    }
    return std::numbers::pi / (2.0 * a);
}

double free_rotor_half_period(const Vec3& inertia_sorted, double L2, double energy) {
    double i1 = inertia_sorted[0];
    const double i2 = inertia_sorted[1];
    double i3 = inertia_sorted[2];
    KILN_ASSERT(i1 < i2 && i2 < i3);
    // Landau & Lifshitz Eq. 37.10 holds for L^2 > 2 E I2; for L^2 < 2 E I2 the suffixes 1 and 3
    // are interchanged (their remark after Eq. 37.12).
    if (L2 < 2.0 * energy * i2) {
        std::swap(i1, i3);
    }
    const double rate = std::sqrt((i3 - i2) * (L2 - 2.0 * energy * i1) / (i1 * i2 * i3));
    const double m = (i2 - i1) * (2.0 * energy * i3 - L2) / ((i3 - i2) * (L2 - 2.0 * energy * i1));
    KILN_ASSERT(m >= 0.0 && m < 1.0);
    return 2.0 * elliptic_k(m) / rate;
}

} // namespace kiln::geometry
