#pragma once
// Superquadric (superellipsoid) solid in its body frame (origin at the centre, axes = principal
// axes). Inside-outside function (Barr 1981; Jaklic, Leonardis & Solina 2000, Eq. 2.10):
//   F(x) = ( |x/a|^(2/e2) + |y/b|^(2/e2) )^(e2/e1) + |z/c|^(2/e1) - 1,
// F < 0 inside, F = 0 on the surface. e1 shapes the x-z and y-z sections ("north-south"), e2 the
// x-y section ("east-west"). A z-axis cylinder is e1 -> 0 (flat ends), e2 = 1 (round section); the
// seed thesis prints these two swapped (Oschmann 2019, L369). Convex for 0 < e <= 2; kiln supports
// kMinExponent <= e1, e2 <= kMaxExponent (see docs/theory/shapes.md for why these bounds).

#include "core/types.hpp"

#include <array>

namespace kiln::geometry {

/// Superquadric with half-axes (m) and blockiness exponents e1, e2 (-), body frame.
struct Superquadric {
    static constexpr double kMinExponent = 0.1; ///< sharper shapes overflow exponents of 2/e
    static constexpr double kMaxExponent = 1.9; ///< 2 is the octahedron limit: creased, no normal

    Vec3 half_axes = Vec3::Ones(); ///< a, b, c along body x, y, z (m)
    double e1 = 1.0;               ///< north-south exponent (x-z and y-z sections) (-)
    double e2 = 1.0;               ///< east-west exponent (x-y section) (-)

    /// Throws kiln::InputError (prefixed by `where`, e.g. "file.toml: exponents") when the
    /// half-axes are not positive or an exponent is outside [kMinExponent, kMaxExponent].
    void validate(const std::string& where) const;

    /// Inside-outside value F(x) (dimensionless, < 0 inside) at a body-frame point (m).
    [[nodiscard]] double inside_outside(const Vec3& p_body) const;
    /// Gradient of F at a body-frame point (1/m), body frame.
    [[nodiscard]] Vec3 gradient(const Vec3& p_body) const;
    /// Hessian of F at a body-frame point (1/m^2), body frame. Written with one pow per term as
    /// the reference form: curvature_tensor() computes the same Hessian with shared powers for
    /// speed, and Superquadric.CurvatureTensorSharesThePowers holds the two together.
    [[nodiscard]] Mat3 hessian(const Vec3& p_body) const;
    /// Outward unit normal at (or near) the surface point p (body frame).
    [[nodiscard]] Vec3 normal(const Vec3& p_body) const { return gradient(p_body).normalized(); }
    /// Surface point in the direction of u from the centre: lambda u with F = 0 (m, body frame).
    [[nodiscard]] Vec3 radial_surface_point(const Vec3& u_body) const;
    /// Surface point of the parametric form (Jaklic et al. 2000, Eq. 2.11) at latitude eta in
    /// [-pi/2, pi/2] and longitude omega in [-pi, pi] (m, body frame).
    [[nodiscard]] Vec3 parametric_point(double eta, double omega) const;
    /// Support point: argmax over the solid of d . x for a body-frame direction d (m, body frame).
    /// Closed form from grad F parallel to d (derivation in docs/theory/shapes.md).
    [[nodiscard]] Vec3 support(const Vec3& d_body) const;
    /// Curvature tensor (1/m) at a surface point p, body frame: the shape operator P H P / |grad F|
    /// (P the projector on the tangent plane); zero along the normal. With `normal_out`, also the
    /// outward unit normal there (body frame).
    [[nodiscard]] Mat3 curvature_tensor(const Vec3& p_body, Vec3* normal_out = nullptr) const;
    /// Principal curvatures (1/m, >= 0 on a convex body; smaller first) at a surface point p.
    /// Radii are their inverses; a flat point gives 0 (infinite radius), a tip (exponent > 1 at a
    /// pole) gives infinity for both (zero radius).
    [[nodiscard]] std::array<double, 2> principal_curvatures(const Vec3& p_body) const;

    /// Volume (m^3), Jaklic et al. 2000, Eq. 2.60: 2 a b c e1 e2 B(e1/2+1, e1) B(e2/2, e2/2).
    [[nodiscard]] double volume() const;
    /// Principal moments of inertia per unit density (m^5), body frame, Jaklic et al. 2000,
    /// Eqs. 2.62-2.64 (written with beta functions, see docs/theory/shapes.md).
    [[nodiscard]] Vec3 inertia_unit_density() const;
    /// Radius of the smallest centred sphere enclosing the body (m).
    [[nodiscard]] double bounding_radius() const;
};

/// Beta function B(x, y) = Gamma(x) Gamma(y) / Gamma(x + y), x, y > 0.
[[nodiscard]] double beta_function(double x, double y);

namespace detail {
/// Cube root of x >= 0 (0, infinity and NaN pass through) without libm, within 1 ulp of the
/// exact root; the support map's roots (superquadric.cpp).
[[nodiscard]] double cube_root(double x);
} // namespace detail

} // namespace kiln::geometry
