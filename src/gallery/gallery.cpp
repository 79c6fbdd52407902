// SPDX-License-Identifier: BSD-3-Clause
// The built-in example systems (gallery/gallery.hpp). Each factory writes its model in the
// coordinates stated in the header, with constraints as automatically differentiated generic
// callables.
#include "ukdyn/gallery/gallery.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "ukdyn/core/autodiff.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/core/nonideal.hpp"

namespace ukdyn::gallery {
namespace {

constexpr double kPi = std::numbers::pi;

// tier 1: a parameter out of range, naming the function, the parameter and its value
void require(bool ok, const char* who, const char* what, double value, const char* expected) {
  if (!ok) {
    std::ostringstream os;
    os << "ukdyn::gallery::" << who << ": " << what << " = " << value << " is out of range ("
       << expected << ")";
    throw std::invalid_argument(os.str());
  }
}

VectorXd vec(std::initializer_list<double> v) {
  VectorXd x(Index(v.size()));
  Index i = 0;
  for (double s : v) x[i++] = s;
  return x;
}

// ---------------------------------------------------------------------------------------------
// planar links in natural coordinates: points are pairs (x, y) of q, point p at q[2p], q[2p+1]

// a straight rigid link from point i to point j (i = −1: the fixed point (px, py)), length L,
// mass m, centre of mass at com_x from i along the link, inertia I_com about its centre of mass
struct Link {
  Index i, j;
  double px, py;
  double L, m, com_x, I_com;
};

// constant mass matrix, gravity force and potential of a set of links:
//   v_G = (1 − c) v_i + c v_j,  w² L² = |v_j − v_i|²  on the constraint manifold, c = com_x / L
//   T = m v_G² / 2 + I_com w² / 2
//     = ½ [v_i; v_j]ᵀ (m [(1−c)², (1−c)c; (1−c)c, c²] + I_com/L² [1, −1; −1, 1]) ⊗ I₂ [v_i; v_j]
//   Q = −m g ((1 − c) e_{y_i} + c e_{y_j}),  V = m g y_G = −Qᵀ q + m g (1 − c) py (fixed i)
struct LinkModel {
  MatrixXd M;
  VectorXd Q;
  double V_const = 0.0;
};

LinkModel assemble_links(Index n, const std::vector<Link>& links, double g) {
  LinkModel out{MatrixXd::Zero(n, n), VectorXd::Zero(n), 0.0};
  for (const Link& k : links) {
    const double c = k.com_x / k.L, rot = k.I_com / (k.L * k.L);
    const double mii = k.m * (1 - c) * (1 - c) + rot, mij = k.m * (1 - c) * c - rot,
                 mjj = k.m * c * c + rot;
    for (Index d = 0; d < 2; ++d) {
      const Index ej = 2 * k.j + d;
      out.M(ej, ej) += mjj;
      if (k.i >= 0) {
        const Index ei = 2 * k.i + d;
        out.M(ei, ei) += mii;
        out.M(ei, ej) += mij;
        out.M(ej, ei) += mij;
      }
    }
    out.Q[2 * k.j + 1] -= k.m * g * c;
    if (k.i >= 0) {
      out.Q[2 * k.i + 1] -= k.m * g * (1 - c);
    } else {
      out.V_const += k.m * g * (1 - c) * k.py;
    }
  }
  return out;
}

// one row per link: (|r_j − r_i|² − L²) / (2 L) = 0, a length error in metres. N rows fixed at
// compile time, so the automatic differentiation passes unroll.
template <std::size_t N>
struct DistanceRows {
  std::array<Link, N> links;

  template <class Vq, class T, class Vout>
  void operator()(const Vq& q, const T&, Vout& phi) const {
    using S = typename Vq::Scalar;
    for (std::size_t r = 0; r < N; ++r) {
      const Link& k = links[r];
      const S dx = k.i < 0 ? S(q[2 * k.j] - k.px) : S(q[2 * k.j] - q[2 * k.i]);
      const S dy = k.i < 0 ? S(q[2 * k.j + 1] - k.py) : S(q[2 * k.j + 1] - q[2 * k.i + 1]);
      phi[Index(r)] = (dx * dx + dy * dy - k.L * k.L) * (0.5 / k.L);
    }
  }
};

template <std::size_t N>
Constraint distance_constraint(std::string name, const std::vector<Link>& links) {
  DistanceRows<N> rows;
  std::copy_n(links.begin(), N, rows.links.begin());
  return holonomic(std::move(name), Index(N), rows);
}

// a system of links in natural coordinates with constant M, gravity and V − V_eq
System link_system(std::vector<std::string> coordinate_names, const std::vector<Link>& links,
                   std::vector<Constraint> constraints, double g, double V_datum) {
  const Index n = Index(coordinate_names.size());
  const LinkModel lm = assemble_links(n, links, g);
  SystemBuilder b(std::move(coordinate_names));
  // Q is constant (gravity), V = −Qᵀ q + V_const − V_datum
  b.mass_matrix(lm.M)
      .forces([Q = lm.Q](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&,
                         double, Eigen::Ref<VectorXd> out) { out = Q; })
      .potential_energy([Q = lm.Q, c = lm.V_const - V_datum](const Eigen::Ref<const VectorXd>& q,
                                                             double) { return -Q.dot(q) + c; });
  for (Constraint& c : constraints) b.add(std::move(c));
  return b.build();
}

// ---------------------------------------------------------------------------------------------
// shared benchmark problems: values copied from bench/data/problems.json at full
// precision (the shortest decimal that round-trips each double of the file)

constexpr double kP1_Veq = -29.43;
constexpr double kP1_L = 1.0, kP1_m = 1.0, kP1_com = 1.0, kP1_I = 1.0000000000000001e-09;
constexpr double kP1_reference = -2.1392711;

constexpr double kP2_Veq = 3.1660572656184334;
constexpr double kP2_crank_L = 0.3, kP2_crank_m = 0.3, kP2_crank_com = 0.15,
                 kP2_crank_I = 0.0022499999999999998;
constexpr double kP2_coupler_L = 1.0, kP2_coupler_m = 1.0, kP2_coupler_com = 0.5,
                 kP2_coupler_I = 0.083333333333333329;
constexpr double kP2_rocker_L = 0.8, kP2_rocker_m = 0.8, kP2_rocker_com = 0.4,
                 kP2_rocker_I = 0.042666666666666679;
constexpr double kP2_Dx = 1.0, kP2_Dy = 0.0;            // rocker pivot D; crank pivot A = (0, 0)
constexpr double kP2_phi_crank0 = 2.6179938779914944;   // 150°
constexpr double kP2_phi_rocker0 = 2.1154295795750078;  // 121.205°, open branch
constexpr double kP2_reference = 3.1507615;

// branch cuts of the reported coordinates (see reported_coordinate in gallery/gallery.hpp)
constexpr double kP1_branch_begin = -1.5 * kPi;
constexpr double kP2_branch_begin = 5.0 * kPi / 12.0;

double on_branch(double phi, double begin) {
  while (phi < begin) phi += 2 * kPi;
  while (phi >= begin + 2 * kPi) phi -= 2 * kPi;
  return phi;
}

void require_shared_q(const char* who, const std::string& name,
                      const Eigen::Ref<const VectorXd>& q) {
  if (q.size() != 4) {
    throw std::invalid_argument(std::string("ukdyn::gallery::") + who + ": q of \"" + name +
                                "\" must have 4 entries, got " + format_number(q.size()));
  }
}

[[noreturn]] void unknown_shared(const char* who, const std::string& name) {
  throw std::invalid_argument(std::string("ukdyn::gallery::") + who + ": \"" + name +
                              "\" is not a shared benchmark problem (known: shared_P1, "
                              "shared_P2)");
}

// ---------------------------------------------------------------------------------------------
// the registry

using Factory = Example (*)();

const std::vector<std::pair<std::string, Factory>>& registry() {
  static const std::vector<std::pair<std::string, Factory>> r = {
      {"pendulum", [] { return pendulum(); }},
      {"bead_on_rotating_wire", [] { return bead_on_rotating_wire(); }},
      {"block_on_incline", [] { return block_on_incline(); }},
      {"chaplygin_sleigh", [] { return chaplygin_sleigh(); }},
      {"double_four_bar", [] { return double_four_bar(); }},
      {"shared_P1", [] { return shared_P1(); }},
      {"shared_P2", [] { return shared_P2(); }},
  };
  return r;
}

}  // namespace

std::vector<std::string> names() {
  std::vector<std::string> out;
  for (const auto& [name, f] : registry()) out.push_back(name);
  return out;
}

Example make(const std::string& name) {
  for (const auto& [known, f] : registry()) {
    if (known == name) return f();
  }
  std::string list;
  for (const auto& [known, f] : registry()) list += (list.empty() ? "" : ", ") + known;
  throw std::invalid_argument("ukdyn::gallery::make: unknown example \"" + name +
                              "\" (known: " + list + ")");
}

// ---------------------------------------------------------------------------------------------

Example pendulum(double m, double L, double g) {
  require(m > 0, "pendulum", "m", m, "> 0");
  require(L > 0, "pendulum", "L", L, "> 0");
  // M = m I, Q = (0, −m g), V = m g y; the rod (x² + y² − L²) / (2L) = 0
  System sys =
      SystemBuilder({"x", "y"})
          .mass_matrix(m * MatrixXd::Identity(2, 2))
          .forces([w = m * g](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&,
                              double, Eigen::Ref<VectorXd> Q) { Q << 0.0, -w; })
          .potential_energy(
              [w = m * g](const Eigen::Ref<const VectorXd>& q, double) { return w * q[1]; })
          .add(holonomic("rod", 1,
                         [L](const auto& q, const auto&, auto& phi) {
                           phi[0] = (q[0] * q[0] + q[1] * q[1] - L * L) * (0.5 / L);
                         }))
          .build();
  std::ostringstream d;
  d.precision(12);
  d << "Planar pendulum in Cartesian coordinates (x, y): mass " << m << " kg on a massless rod "
    << "of " << L << " m (holonomic constraint \"rod\"), gravity " << g << " m/s^2 along -y, "
    << "released horizontally at rest from (L, 0). Period 4 sqrt(L/g) K(1/2) (2.367841947576 s "
    << "for L = 1, g = 9.81); rod tension 3 m g cos(theta) = -3 m g y / L; E = 0 throughout.";
  return {"pendulum", d.str(), std::move(sys), vec({L, 0.0}), vec({0.0, 0.0}), 10.0};
}

Example bead_on_rotating_wire(double m, double Omega, double r0, double rd0) {
  require(m > 0, "bead_on_rotating_wire", "m", m, "> 0");
  require(Omega != 0, "bead_on_rotating_wire", "Omega", Omega, "non-zero");
  // the wire through the origin along u(t) = (cos Ωt, sin Ωt): n(t) · q = 0
  System sys = SystemBuilder({"x", "y"})
                   .mass_matrix(m * MatrixXd::Identity(2, 2))
                   .add(holonomic("wire", 1,
                                  [Omega](const auto& q, const auto& t, auto& phi) {
                                    using std::cos;
                                    using std::sin;
                                    phi[0] = -q[0] * sin(Omega * t) + q[1] * cos(Omega * t);
                                  }))
                   .build();
  std::ostringstream d;
  d.precision(12);
  d << "Bead of " << m << " kg in a horizontal plane, Cartesian coordinates (x, y), on a "
    << "straight wire through the origin turning at Omega = " << Omega << " rad/s (rheonomic "
    << "holonomic constraint \"wire\": -x sin(Omega t) + y cos(Omega t) = 0). "
    << "r(t) = r0 cosh(Omega t) + (r0'/Omega) sinh(Omega t) with r0 = " << r0 << " m, r0' = " << rd0
    << " m/s; the wire pushes 2 m Omega r' across itself and does work.";
  return {"bead_on_rotating_wire", d.str(), std::move(sys), vec({r0, 0.0}),
          vec({rd0, r0 * Omega}),  2.0};
}

Example block_on_incline(double alpha, double mu, double v0, double m, double g) {
  require(alpha >= 0 && alpha < kPi / 2, "block_on_incline", "alpha", alpha, "[0, pi/2)");
  require(mu >= 0, "block_on_incline", "mu", mu, ">= 0");
  require(m > 0, "block_on_incline", "m", m, "> 0");
  const double s = std::sin(alpha), c = std::cos(alpha);
  // the plane through the origin rising at alpha; its signed distance −x sin α + y cos α = 0
  System sys =
      SystemBuilder({"x", "y"})
          .mass_matrix(m * MatrixXd::Identity(2, 2))
          .forces([w = m * g](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&,
                              double, Eigen::Ref<VectorXd> Q) { Q << 0.0, -w; })
          .potential_energy(
              [w = m * g](const Eigen::Ref<const VectorXd>& q, double) { return w * q[1]; })
          .add(holonomic(
              "incline", 1,
              [s, c](const auto& q, const auto&, auto& phi) { phi[0] = -q[0] * s + q[1] * c; }))
          .add(coulomb_friction({.constraint = "incline", .mu = mu, .coordinates = {0, 1}}))
          .build();
  const double decel = g * (s + mu * c);
  std::ostringstream d;
  d.precision(12);
  d << "Block of " << m << " kg, Cartesian coordinates (x, y), launched at " << v0
    << " m/s up a rough incline of angle " << alpha << " rad (holonomic constraint "
    << "\"incline\") with Coulomb friction mu = " << mu << " (non-ideal force "
    << "\"coulomb.incline\", normal force from the incline's ideal reaction). Deceleration "
    << "g (sin alpha + mu cos alpha) = " << decel << " m/s^2; stops at t = " << v0 / decel
    << " s after " << v0 * v0 / (2 * decel) << " m"
    << (mu > std::tan(alpha) ? ", then sticks" : ", then slides back") << ".";
  return {"block_on_incline", d.str(), std::move(sys), vec({0.0, 0.0}), vec({v0 * c, v0 * s}), 1.0};
}

Example chaplygin_sleigh(double m, double a, double I, double w0, double v0) {
  require(m > 0, "chaplygin_sleigh", "m", m, "> 0");
  require(I > 0, "chaplygin_sleigh", "I", I, "> 0");
  // knife edge at P = G − a u: v_P · n = −x' sin θ + y' cos θ − a θ' = 0
  System sys = SystemBuilder({"x", "y", "theta"})
                   .mass_matrix(vec({m, m, I}).asDiagonal().toDenseMatrix())
                   .add(nonholonomic("knife_edge", 1,
                                     [a](const auto& q, const auto& qd, const auto&, auto& psi) {
                                       using std::cos;
                                       using std::sin;
                                       psi[0] = -qd[0] * sin(q[2]) + qd[1] * cos(q[2]) - a * qd[2];
                                     }))
                   .build();
  const double k = m * a / (I + m * a * a), V = std::sqrt(v0 * v0 + (I + m * a * a) * w0 * w0 / m);
  std::ostringstream d;
  d.precision(12);
  d << "Chaplygin sleigh: body of " << m << " kg, inertia " << I << " kg m^2 about its centre of "
    << "mass G, knife edge a = " << a << " m behind G; coordinates (x, y, theta) of G and the "
    << "heading; nonholonomic constraint \"knife_edge\". The contact point's speed v (= G's "
    << "velocity along the body axis) obeys v(t) = V tanh(k V t + atanh(v0/V)), V = " << V
    << " m/s, k = " << k << " 1/m"
    << " (v0 = " << v0 << " m/s, w0 = " << w0 << " rad/s).";
  return {"chaplygin_sleigh",    d.str(), std::move(sys), vec({0.0, 0.0, 0.0}),
          vec({v0, a * w0, w0}), 30.0};
}

Example double_four_bar() {
  const double L = 1.0, m = 1.0;
  // cranks from the fixed pivots (k, 0) to tip k; couplers between consecutive tips
  const std::vector<Link> links = {{-1, 0, 0.0, 0.0, L, m, L / 2, m * L * L / 12},
                                   {-1, 1, 1.0, 0.0, L, m, L / 2, m * L * L / 12},
                                   {-1, 2, 2.0, 0.0, L, m, L / 2, m * L * L / 12},
                                   {0, 1, 0.0, 0.0, L, m, L / 2, m * L * L / 12},
                                   {1, 2, 0.0, 0.0, L, m, L / 2, m * L * L / 12}};
  std::vector<Constraint> constraints;
  const char* constraint_names[] = {"crank1", "crank2", "crank3", "coupler1", "coupler2"};
  for (std::size_t k = 0; k < links.size(); ++k) {
    constraints.push_back(distance_constraint<1>(constraint_names[k], {links[k]}));
  }
  // V = m g (y1 + 3/2 y2 + y3) + 0: pivots at y = 0, no datum shift
  System sys = link_system({"x1", "y1", "x2", "y2", "x3", "y3"}, links, std::move(constraints),
                           kGravity, 0.0);
  std::string d =
      "IFToMM benchmark A02, double four-bar mechanism: five uniform 1 m, 1 kg rods; cranks "
      "pivoted at (0,0), (1,0), (2,0), initially vertical; couplers horizontal at y = 1; crank "
      "tips start at 1 m/s along +x; gravity 9.81 m/s^2 along -y. Natural coordinates: the three "
      "crank tips (6), five distance constraints (crank1..3, coupler1..2), one degree of freedom "
      "with a redundant crank and singular configurations when the cranks are horizontal. "
      "Reference: left crank tip at t = 10 s is (0.32845811, 0.94451854).";
  return {"double_four_bar",
          std::move(d),
          std::move(sys),
          vec({0.0, 1.0, 1.0, 1.0, 2.0, 1.0}),
          vec({1.0, 0.0, 1.0, 0.0, 1.0, 0.0}),
          10.0};
}

Example shared_P1() {
  // link 1 from the pivot to tip 1 (point 0), link 2 from tip 1 to tip 2 (point 1)
  const std::vector<Link> links = {{-1, 0, 0.0, 0.0, kP1_L, kP1_m, kP1_com, kP1_I},
                                   {0, 1, 0.0, 0.0, kP1_L, kP1_m, kP1_com, kP1_I}};
  std::vector<Constraint> constraints;
  constraints.push_back(distance_constraint<2>("links", links));
  System sys =
      link_system({"x1", "y1", "x2", "y2"}, links, std::move(constraints), kGravity, kP1_Veq);
  std::string d =
      "Shared benchmark P1: double pendulum, massless 1 m links with 1 kg at each tip (I_com = "
      "1e-9), pivot at the origin, released at rest with both links along +x, gravity 9.81; "
      "natural coordinates (x1, y1, x2, y2) of the tips, holonomic constraint \"links\" (2 "
      "rows). V from V_eq = -29.43 J. Reference phi_link1(10 s) = -2.1392711 rad.";
  return {"shared_P1",       std::move(d), std::move(sys), vec({kP1_L, 0.0, 2 * kP1_L, 0.0}),
          VectorXd::Zero(4), 10.0};
}

Example shared_P2() {
  // crank A → B (point 0), coupler B → C (point 1), rocker D → C
  const std::vector<Link> links = {
      {-1, 0, 0.0, 0.0, kP2_crank_L, kP2_crank_m, kP2_crank_com, kP2_crank_I},
      {0, 1, 0.0, 0.0, kP2_coupler_L, kP2_coupler_m, kP2_coupler_com, kP2_coupler_I},
      {-1, 1, kP2_Dx, kP2_Dy, kP2_rocker_L, kP2_rocker_m, kP2_rocker_com, kP2_rocker_I}};
  std::vector<Constraint> constraints;
  constraints.push_back(distance_constraint<3>("links", links));
  System sys =
      link_system({"xB", "yB", "xC", "yC"}, links, std::move(constraints), kGravity, kP2_Veq);
  // B from the crank angle, C from the rocker angle (the closure holds to 1.6e-16)
  const VectorXd q0 =
      vec({kP2_crank_L * std::cos(kP2_phi_crank0), kP2_crank_L * std::sin(kP2_phi_crank0),
           kP2_Dx + kP2_rocker_L * std::cos(kP2_phi_rocker0),
           kP2_Dy + kP2_rocker_L * std::sin(kP2_phi_rocker0)});
  std::string d =
      "Shared benchmark P2: crank-rocker four-bar, crank 0.3 m, coupler 1.0 m, rocker 0.8 m, "
      "ground 1.0 m, uniform thin rods of 1 kg/m, pivots A = (0,0) and D = (1,0), crank released "
      "at rest at 150 deg on the open branch, gravity 9.81; natural coordinates (xB, yB, xC, yC) "
      "of the crank tip and of the coupler tip (= rocker tip), holonomic constraint \"links\" (3 "
      "rows). V from V_eq = 3.1660572656184334 J. Reference phi_crank(10 s) = 3.1507615 rad.";
  return {"shared_P2", std::move(d), std::move(sys), q0, VectorXd::Zero(4), 10.0};
}

double reported_coordinate(const std::string& name, const Eigen::Ref<const VectorXd>& q) {
  if (name == "shared_P1") {
    require_shared_q("reported_coordinate", name, q);
    return on_branch(std::atan2(q[1], q[0]), kP1_branch_begin);
  }
  if (name == "shared_P2") {
    require_shared_q("reported_coordinate", name, q);
    return on_branch(std::atan2(q[1], q[0]), kP2_branch_begin);
  }
  unknown_shared("reported_coordinate", name);
}

double closure_violation(const std::string& name, const Eigen::Ref<const VectorXd>& q) {
  if (name == "shared_P1") {
    require_shared_q("closure_violation", name, q);
    return 0.0;
  }
  if (name == "shared_P2") {
    require_shared_q("closure_violation", name, q);
    const Eigen::Vector2d B = q.segment<2>(0), C = q.segment<2>(2), D(kP2_Dx, kP2_Dy);
    // place each link from its proximal point along its direction, with its exact length
    const Eigen::Vector2d crank_tip = kP2_crank_L * B.normalized();
    const Eigen::Vector2d coupler_tip = crank_tip + kP2_coupler_L * (C - B).normalized();
    const Eigen::Vector2d rocker_tip = D + kP2_rocker_L * (C - D).normalized();
    return (coupler_tip - rocker_tip).norm();
  }
  unknown_shared("closure_violation", name);
}

SharedProblem shared_problem(const std::string& name) {
  if (name == "shared_P1") return {"P1", "phi_link1", 10.0, kP1_Veq, kP1_reference};
  if (name == "shared_P2") return {"P2", "phi_crank", 10.0, kP2_Veq, kP2_reference};
  unknown_shared("shared_problem", name);
}

}  // namespace ukdyn::gallery
