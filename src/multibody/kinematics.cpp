// SPDX-License-Identifier: BSD-3-Clause
// Body kinematics in closed form and the joint constraint model built on it: every joint row is
// a dot product of two vector expressions (body vectors R s, point differences), a distance, or
// a linear combination of coordinates, whose A and b follow from the kinematics of its vectors.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "multibody/internal.hpp"

namespace ukdyn::mb::detail {

BodyRef body_ref(const std::vector<BodyInfo>& bodies, BodyId id) {
  if (id == kGround) return {};
  const BodyInfo& b = bodies.at(std::size_t(id));
  return {b.kind, b.offset, 0, id};
}

CosSin cos_sin_of(double theta) {
  // glibc's sincos: one argument reduction for both, bitwise std::cos and std::sin (the same
  // kernels; GCC does not merge the two calls by itself without -ffast-math)
  CosSin cs;
  ::sincos(theta, &cs.s, &cs.c);
  return cs;
}

PoseCache::PoseCache(Index bodies) : trig_(std::size_t(bodies)), rotation_(std::size_t(bodies)) {
  // every entry starts as a valid memo: theta = 0
  const CosSin zero = cos_sin_of(0.0);
  for (Trig& e : trig_) e = {std::bit_cast<std::uint64_t>(0.0), zero.c, zero.s};
}

const Matrix3d& PoseCache::rotation(const BodyRef& b, const Eigen::Ref<const VectorXd>& q) {
  Rotation& e = rotation_[std::size_t(b.id)];
  // the orientation coordinates: planar theta; rigid u0..u3
  const Index first = b.kind == BodyKind::kPlanar ? b.offset + 2 : b.offset + 3;
  const int count = b.kind == BodyKind::kPlanar ? 1 : 4;
  std::array<std::uint64_t, 4> key{};
  for (int i = 0; i < count; ++i) key[std::size_t(i)] = std::bit_cast<std::uint64_t>(q[first + i]);
  if (!e.valid || key != e.key) {
    e.R = rotation_WB(b, q, nullptr);
    e.key = key;
    e.valid = true;
    ++computed_;
  }
  return e.R;
}

void add_body_vector(const BodyRef& b, const Eigen::Ref<const VectorXd>& q,
                     const Eigen::Ref<const VectorXd>& qd, const Vector3d& s, bool translate,
                     double sign, VecKin& k, PoseCache* cache, bool second_order) {
  if (b.ground()) {
    k.x += sign * s;
    return;
  }
  const Index o = b.offset, l = b.local;
  switch (b.kind) {
    case BodyKind::kParticle:
      // x = r + s: J = I, v = r', g = 0
      k.x += sign * s;
      if (translate) {
        k.x += sign * q.segment<3>(o);
        k.v += sign * qd.segment<3>(o);
        if (second_order) k.J.block<3, 3>(0, l) += sign * Matrix3d::Identity();
      }
      break;
    case BodyKind::kPlanar: {
      // x = (x, y, 0) + R(theta) s: dx/dtheta = e_z × R s, g = −theta'² (R s)_xy
      const CosSin cs = planar_cos_sin(cache, b, q[o + 2]);
      const double c = cs.c, sn = cs.s, w = qd[o + 2];
      const double rx = c * s.x() - sn * s.y(), ry = sn * s.x() + c * s.y();
      k.x += sign * Vector3d(rx, ry, s.z());
      k.v += sign * w * Vector3d(-ry, rx, 0.0);
      if (second_order) {
        k.g += sign * (-w * w) * Vector3d(rx, ry, 0.0);
        k.J(0, l + 2) += sign * -ry;
        k.J(1, l + 2) += sign * rx;
      }
      if (translate) {
        k.x += sign * Vector3d(q[o], q[o + 1], 0.0);
        k.v += sign * Vector3d(qd[o], qd[o + 1], 0.0);
        if (second_order) {
          k.J(0, l) += sign;
          k.J(1, l + 1) += sign;
        }
      }
      break;
    }
    case BodyKind::kRigid: {
      // x = r + R(u) s: J = [I, D(u, s)], v = r' + D(u, s) u', g = 2 R(u') s
      const Vector4d u = q.segment<4>(o + 3), ud = qd.segment<4>(o + 3);
      const Matrix34 D = rotate_jacobian(u, s);
      k.x += sign * rotate(u, s);
      k.v += sign * (D * ud);
      if (second_order) {
        k.g += sign * 2.0 * rotate(ud, s);
        k.J.block<3, 4>(0, l + 3) += sign * D;
      }
      if (translate) {
        k.x += sign * q.segment<3>(o);
        k.v += sign * qd.segment<3>(o);
        if (second_order) k.J.block<3, 3>(0, l) += sign * Matrix3d::Identity();
      }
      break;
    }
  }
}

namespace {
// (R(theta) s)_xy of a planar body and its theta' (the ground: s_xy, at rest)
struct PlanarPoint {
  double rx, ry, w;
};
inline PlanarPoint planar_point(const BodyRef& b, const Eigen::Ref<const VectorXd>& q,
                                const Eigen::Ref<const VectorXd>& qd, const Vector3d& s,
                                PoseCache* cache) {
  if (b.ground()) return {s.x(), s.y(), 0.0};
  const CosSin cs = planar_cos_sin(cache, b, q[b.offset + 2]);
  const double c = cs.c, sn = cs.s;
  return {c * s.x() - sn * s.y(), sn * s.x() + c * s.y(), qd[b.offset + 2]};
}

// the same vector expression (rows of one joint often share one: d·e_x, d·e_y of a revolute)
bool same_expr(const VecExpr& e, const VecExpr& f) {
  return e.kind == f.kind && e.slot_a == f.slot_a && e.slot_b == f.slot_b && e.s_a == f.s_a &&
         e.s_b == f.s_b && e.world == f.world;
}
// row r's first vector is the previous row's: its kinematics in ka can be reused
bool reuses_a(const std::vector<Row>& rows, std::size_t r) {
  return r > 0 && rows[r].kind != Row::kLinear && rows[r - 1].kind != Row::kLinear &&
         same_expr(rows[r].a, rows[r - 1].a);
}

// the PoseCache of a JointModel's scratch (null: none, every rotation is computed)
PoseCache* cache_of(ConstraintScratch* scratch) {
  return scratch != nullptr ? static_cast<JointModel::Scratch*>(scratch)->cache : nullptr;
}
}  // namespace

JointModel::JointModel(std::vector<BodyRef> slots, std::vector<Row> rows)
    : slots_(std::move(slots)), rows_(std::move(rows)) {
  // local columns: the bodies' coordinates by increasing offset (each body once)
  std::vector<Index> order;
  for (const BodyRef& s : slots_) {
    if (!s.ground()) order.push_back(s.offset);
  }
  std::sort(order.begin(), order.end());
  order.erase(std::unique(order.begin(), order.end()), order.end());
  for (Index o : order) {
    for (BodyRef& s : slots_) {
      if (s.offset == o) s.local = Index(cols_.size());
    }
    const auto it =
        std::find_if(slots_.begin(), slots_.end(), [o](const BodyRef& s) { return s.offset == o; });
    for (Index i = 0; i < it->size(); ++i) cols_.push_back(o + i);
  }
  // linear rows: the local column of each term
  for (Row& r : rows_) {
    r.local.clear();
    for (const auto& [i, coef] : r.terms) {
      const auto c = std::find(cols_.begin(), cols_.end(), i);
      if (c == cols_.end()) {
        throw std::logic_error("ukdyn::mb: a linear joint row refers to a coordinate of no body");
      }
      r.local.push_back(Index(c - cols_.begin()));
    }
  }
  // the planar revolute pattern: d = o_C − o_P dotted with e_x and e_y, constant offsets 0
  const auto planar_or_ground = [this](int slot) {
    return slot >= 0 && slot < int(slots_.size()) &&
           (slots_[std::size_t(slot)].ground() ||
            slots_[std::size_t(slot)].kind == BodyKind::kPlanar);
  };
  const auto axis_row = [&](const Row& r, const Vector3d& axis) {
    return r.kind == Row::kDot && r.a.kind == VecExpr::kPointDiff && r.b.kind == VecExpr::kWorld &&
           r.b.world == axis && !r.c.motion && r.c.c0 == 0.0 && planar_or_ground(r.a.slot_a) &&
           planar_or_ground(r.a.slot_b);
  };
  for (const BodyRef& s : slots_) max_id_ = std::max(max_id_, s.id);
  if (rows_.size() > std::size_t(kMaxRows) || cols_.size() > std::size_t(kMaxCols)) {
    throw std::logic_error(
        "ukdyn::mb: a joint model has more rows or columns than kMaxRows, "
        "kMaxCols");
  }
  planar_revolute_ = rows_.size() == 2 && axis_row(rows_[0], Vector3d::UnitX()) &&
                     axis_row(rows_[1], Vector3d::UnitY()) &&
                     rows_[0].a.slot_a == rows_[1].a.slot_a &&
                     rows_[0].a.slot_b == rows_[1].a.slot_b && rows_[0].a.s_a == rows_[1].a.s_a &&
                     rows_[0].a.s_b == rows_[1].a.s_b &&
                     (slots_[std::size_t(rows_[0].a.slot_a)].ground() ||
                      slots_[std::size_t(rows_[0].a.slot_b)].ground() ||
                      slots_[std::size_t(rows_[0].a.slot_a)].offset !=
                          slots_[std::size_t(rows_[0].a.slot_b)].offset);
  reuses_a_.resize(rows_.size());
  for (std::size_t r = 0; r < rows_.size(); ++r) reuses_a_[r] = reuses_a(rows_, r) ? 1 : 0;
}

std::unique_ptr<ConstraintScratch> JointModel::make_scratch(Index) const {
  auto s = std::make_unique<Scratch>();
  s->own = std::make_unique<PoseCache>(max_id_ + 1);
  s->cache = s->own.get();
  return s;
}

std::unique_ptr<ConstraintScratch> JointModel::make_scratch_sharing(Index n,
                                                                    CallableScratch* shared) const {
  // the multibody System's callables' scratch is its PoseCache; any other (this joint's
  // constraint inside another system) or none: a cache of its own
  auto* cache = dynamic_cast<PoseCache*>(shared);
  if (cache == nullptr || cache->body_count() <= max_id_) return make_scratch(n);
  auto s = std::make_unique<Scratch>();
  s->cache = cache;
  return s;
}

void JointModel::eval(const VecExpr& e, const Eigen::Ref<const VectorXd>& q,
                      const Eigen::Ref<const VectorXd>& qd, PoseCache* cache, VecKin& k,
                      bool second_order) const {
  k.clear(second_order);
  switch (e.kind) {
    case VecExpr::kWorld:
      k.x = e.world;
      break;
    case VecExpr::kBodyVector:
      add_body_vector(slots_[std::size_t(e.slot_a)], q, qd, e.s_a, false, 1.0, k, cache,
                      second_order);
      break;
    case VecExpr::kPointDiff:
      add_body_vector(slots_[std::size_t(e.slot_b)], q, qd, e.s_b, true, 1.0, k, cache,
                      second_order);
      add_body_vector(slots_[std::size_t(e.slot_a)], q, qd, e.s_a, true, -1.0, k, cache,
                      second_order);
      break;
  }
}

void JointModel::acceleration_form(const Eigen::Ref<const VectorXd>& q,
                                   const Eigen::Ref<const VectorXd>& qd, double t,
                                   ConstraintScratch* scratch, Eigen::Ref<MatrixXd> A,
                                   Eigen::Ref<VectorXd> b) const {
  const Index k = local_count();
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, kMaxRows, kMaxCols> local(
      A.rows(), k);
  acceleration_form_local(q, qd, t, scratch, local, b);
  // column by column: a local column where columns() has one, zeros elsewhere
  const Index rows = A.rows(), n = A.cols(), stride = A.outerStride();
  double* a = A.data();
  const double* l = local.data();
  Index j = 0;  // the next local column
  for (Index c = 0; c < n; ++c, a += stride) {
    if (j < k && cols_[std::size_t(j)] == c) {
      for (Index i = 0; i < rows; ++i) a[i] = l[i];
      l += rows;
      ++j;
    } else {
      for (Index i = 0; i < rows; ++i) a[i] = 0.0;
    }
  }
}

void JointModel::acceleration_form_local(const Eigen::Ref<const VectorXd>& q,
                                         const Eigen::Ref<const VectorXd>& qd, double t,
                                         ConstraintScratch* scratch, Eigen::Ref<MatrixXd> A,
                                         Eigen::Ref<VectorXd> b) const {
  PoseCache* const cache = cache_of(scratch);
  if (planar_revolute_) {
    // phi = (x_C + R_C s_C − x_P − R_P s_P)_xy:  A = ±[I | e_z × R s] on each body,
    // b = Σ ± theta'² R s  (the dot rows' A = e_iᵀ J_d, b = −e_i·g_d, g = −theta'² R s)
    // The two bodies' columns tile the local ones (the constructor checks it), so every entry
    // of A is written once: each is the sum on zero of its one term, written out as such
    // (0 + x and 0 − x, which differ from x and −x in the sign of a zero).
    const VecExpr& d = rows_[0].a;
    double b0 = 0.0, b1 = 0.0;
    for (int side = 0; side < 2; ++side) {
      const BodyRef& body = slots_[std::size_t(side == 0 ? d.slot_b : d.slot_a)];
      if (body.ground()) continue;
      const double sign = side == 0 ? 1.0 : -1.0;
      const PlanarPoint p = planar_point(body, q, qd, side == 0 ? d.s_b : d.s_a, cache);
      const Index l = body.local;
      A(0, l) = 0.0 + sign;
      A(1, l) = 0.0;
      A(0, l + 1) = 0.0;
      A(1, l + 1) = 0.0 + sign;
      A(0, l + 2) = 0.0 - sign * p.ry;
      A(1, l + 2) = 0.0 + sign * p.rx;
      b0 += sign * p.w * p.w * p.rx;
      b1 += sign * p.w * p.w * p.ry;
    }
    b[0] = b0;
    b[1] = b1;
    return;
  }
  general_form(q, qd, t, cache, A, b);
}

void JointModel::general_form(const Eigen::Ref<const VectorXd>& q,
                              const Eigen::Ref<const VectorXd>& qd, double t, PoseCache* cache,
                              Eigen::Ref<MatrixXd> A, Eigen::Ref<VectorXd> b) const {
  const Index k = local_count();
  // (every use is preceded by eval, which clears what it writes)
  VecKin ka{VecKin::Unset{}}, kb{VecKin::Unset{}};
  for (std::size_t r = 0; r < rows_.size(); ++r) {
    const Row& row = rows_[r];
    const Index i = Index(r);
    switch (row.kind) {
      case Row::kDot: {
        // phi = a·b − c:  A = bᵀ J_a + aᵀ J_b,  b = −(g_a·b + 2 v_a·v_b + a·g_b) + c''
        if (!reuses_a_[r]) eval(row.a, q, qd, cache, ka);
        if (row.b.kind == VecExpr::kWorld) {
          // a constant b (a world axis): A = bᵀ J_a,  b = −g_a·b
          A.row(i) = row.b.world.transpose() * ka.J.leftCols(k);
          b[i] = -ka.g.dot(row.b.world);
        } else {
          eval(row.b, q, qd, cache, kb);
          A.row(i) = (kb.x.transpose() * ka.J.leftCols(k) + ka.x.transpose() * kb.J.leftCols(k));
          b[i] = -(ka.g.dot(kb.x) + 2.0 * ka.v.dot(kb.v) + ka.x.dot(kb.g));
        }
        if (row.c.motion) b[i] += row.c.at(t)[2];
        break;
      }
      case Row::kDistance: {
        // phi = (a·a − L²)/(2L):  A = aᵀ J_a / L,  b = −(a·g_a + v_a·v_a) / L
        if (!reuses_a_[r]) eval(row.a, q, qd, cache, ka);
        A.row(i) = ka.x.transpose() * ka.J.leftCols(k) / row.length;
        b[i] = -(ka.x.dot(ka.g) + ka.v.squaredNorm()) / row.length;
        break;
      }
      case Row::kNorm: {
        // phi = σ (|a| − L), u = a/|a|:  A = σ uᵀ J_a,  b = −σ (u·g_a + (|v_a|² − (u·v_a)²) / |a|)
        // (σ = −1: a sphere inside another; |a| = 0, coincident centres: non-finite entries,
        // which stop the run)
        if (!reuses_a_[r]) eval(row.a, q, qd, cache, ka);
        const double len = ka.x.norm();
        const Vector3d u = ka.x / len;
        const double un = u.dot(ka.v);
        A.row(i) = row.sign * (u.transpose() * ka.J.leftCols(k));
        b[i] = -row.sign * (u.dot(ka.g) + (ka.v.squaredNorm() - un * un) / len);
        break;
      }
      case Row::kLinear: {
        // phi = Σ coef q_i − c:  A = coef,  b = c''
        A.row(i).setZero();
        for (std::size_t z = 0; z < row.terms.size(); ++z) {
          A(i, row.local[z]) += row.terms[z].second;
        }
        b[i] = row.c.motion ? row.c.at(t)[2] : 0.0;
        break;
      }
      case Row::kDisk:
        disk_form(row, i, q, qd, cache, ka, kb, A, b);
        break;
      case Row::kDiskSphere: {
        eval(row.a, q, qd, cache, ka);
        eval(row.axis, q, qd, cache, kb);
        const DiskSphereGap d = disk_sphere_gap(ka, kb, row.length, row.sphere, true);
        A.row(i) = d.A.leftCols(k);
        b[i] = d.b;
        break;
      }
      case Row::kSphereBox: {
        VecKin axes[3] = {VecKin{VecKin::Unset{}}, VecKin{VecKin::Unset{}},
                          VecKin{VecKin::Unset{}}};
        eval(row.a, q, qd, cache, ka);
        for (int z = 0; z < row.box_axes; ++z) eval(row.box[z], q, qd, cache, axes[z]);
        const SphereBoxGap d = sphere_box_gap(ka, axes, row.box_axes, row.half, row.length, true);
        A.row(i) = d.A.leftCols(k);
        b[i] = d.b;
        break;
      }
    }
  }
}

void JointModel::disk_form(const Row& row, Index i, const Eigen::Ref<const VectorXd>& q,
                           const Eigen::Ref<const VectorXd>& qd, PoseCache* cache, VecKin& kd,
                           VecKin& kn, Eigen::Ref<MatrixXd> A, Eigen::Ref<VectorXd> b) const {
  // phi = n·d − r h, h = sqrt(1 − s²), s = n·a:
  //   phi'' = [n·d]'' + (r s / h) s'' + r s'² / h³
  // with [n·d]'' = A_nd q'' − b_nd and s'' = A_s q'' − b_s (the dot rows), so
  //   A = A_nd + (r s / h) A_s,  b = b_nd + (r s / h) b_s − r s'² / h³
  // (h = 0, a disk lying flat: infinite entries, which stop the run; docs/contact.md)
  const Index k = local_count();
  VecKin ku{VecKin::Unset{}};
  eval(row.a, q, qd, cache, kd);
  eval(row.b, q, qd, cache, kn);
  eval(row.axis, q, qd, cache, ku);
  const double s = kn.x.dot(ku.x);
  const double sd = kn.v.dot(ku.x) + kn.x.dot(ku.v);
  const double h = std::sqrt(std::max(1.0 - s * s, 0.0));
  const double r = row.length;
  const double f = r * s / h;
  A.row(i) = kn.x.transpose() * kd.J.leftCols(k) + kd.x.transpose() * kn.J.leftCols(k) +
             f * (ku.x.transpose() * kn.J.leftCols(k) + kn.x.transpose() * ku.J.leftCols(k));
  b[i] = -(kd.g.dot(kn.x) + 2.0 * kd.v.dot(kn.v) + kd.x.dot(kn.g)) -
         f * (kn.g.dot(ku.x) + 2.0 * kn.v.dot(ku.v) + kn.x.dot(ku.g)) - r * sd * sd / (h * h * h);
}

DiskSphereGap disk_sphere_gap(const VecKin& e, const VecKin& k, double radius, double sphere,
                              bool second_order) {
  DiskSphereGap out;
  const double s = k.x.dot(e.x), sd = k.v.dot(e.x) + k.x.dot(e.v);
  const Vector3d w = e.x - s * k.x, wd = e.v - sd * k.x - s * k.v;
  const double rho = w.norm();
  const bool rim = rho > radius;
  // ŵ, m = ρ − radius and m' = ŵ·w' on the rim; m = m' = 0 on the face
  const Vector3d u = rim ? Vector3d(w / rho) : Vector3d::Zero();
  const double m = rim ? rho - radius : 0.0, md = rim ? u.dot(wd) : 0.0;
  const double E = std::sqrt(s * s + m * m);
  out.g = E - sphere;
  out.rate = (s * sd + m * md) / E;
  out.a = rim ? Vector3d(-radius * u) : Vector3d(-w);
  out.a_rate = rim ? Vector3d(-radius * (wd - md * u) / rho) : Vector3d(-wd);
  const Vector3d f = e.x + out.a, fd = e.v + out.a_rate;
  out.n = f / E;
  out.n_rate = (fd - out.n.dot(fd) * out.n) / E;
  if (!second_order) return out;
  // s'' = A_s q'' − b_s (the dot row of k·e)
  const Eigen::Matrix<double, 1, kMaxCols> As = k.x.transpose() * e.J + e.x.transpose() * k.J;
  const double bs = -(e.g.dot(k.x) + 2.0 * e.v.dot(k.v) + e.x.dot(k.g));
  out.A = s * As;
  out.b = s * bs;
  if (rim) {
    // m'' = ŵ·w'' + (|w'|² − m'²)/ρ, w'' = e'' − s'' k − 2 s' k' − s k'':
    //   A_m = ŵᵀ (J_e − s J_k) − (ŵ·k) A_s,
    //   b_m = −(ŵ·(g_e − 2 s' k' − s g_k) + (ŵ·k) b_s + (|w'|² − m'²)/ρ)
    // (ŵ·k = 0 for a unit axis; kept, so that A and b are the derivatives of g for any q)
    const double uk = u.dot(k.x);
    const Eigen::Matrix<double, 1, kMaxCols> Am = u.transpose() * (e.J - s * k.J) - uk * As;
    const double bm =
        -(u.dot(e.g - 2.0 * sd * k.v - s * k.g) + uk * bs + (wd.squaredNorm() - md * md) / rho);
    out.A += m * Am;
    out.b += m * bm;
  }
  const double c = m * sd - s * md;
  out.A /= E;
  out.b = out.b / E - c * c / (E * E * E);
  return out;
}

SphereBoxGap sphere_box_gap(const VecKin& e, const VecKin* k, int axes, const Vector3d& half,
                            double radius, bool second_order) {
  SphereBoxGap out;
  // u_i = k_i·e and u_i', σ_i, the excesses m_i (> 0: a face's region along axis i) and the
  // deepest face (inside)
  double u[3] = {0, 0, 0}, ud[3] = {0, 0, 0}, sigma[3] = {1, 1, 1}, m[3] = {0, 0, 0};
  double sum = 0.0, deepest = 0.0;
  int face = 0;
  for (int i = 0; i < axes; ++i) {
    u[i] = k[i].x.dot(e.x);
    ud[i] = k[i].v.dot(e.x) + k[i].x.dot(e.v);
    sigma[i] = u[i] < 0.0 ? -1.0 : 1.0;
    const double excess = sigma[i] * u[i] - half[i];
    if (excess > 0.0) {
      m[i] = excess;
      sum += excess * excess;
    }
    if (i == 0 || excess > deepest) {
      deepest = excess;
      face = i;
    }
  }
  out.inside = !(sum > 0.0);
  // w_i: the weight of u_i in g (σ_i m_i / E outside, σ_j on the nearest face inside)
  double w[3] = {0, 0, 0};
  double E = 0.0;
  if (out.inside) {
    w[face] = sigma[face];
    out.g = deepest - radius;
  } else {
    E = std::sqrt(sum);
    for (int i = 0; i < axes; ++i) w[i] = sigma[i] * m[i] / E;
    out.g = E - radius;
  }
  Vector3d nd_part = Vector3d::Zero();
  for (int i = 0; i < axes; ++i) {
    out.rate += w[i] * ud[i];
    out.n += w[i] * k[i].x;
    nd_part += w[i] * k[i].v;
  }
  // n' = Σ (w_i' k_i + w_i k_i'), w_i' = σ_i (m_i' − m_i g'/E)/E outside (0 inside)
  out.n_rate = nd_part;
  if (!out.inside) {
    for (int i = 0; i < axes; ++i) {
      if (m[i] > 0.0)
        out.n_rate += sigma[i] * (sigma[i] * ud[i] - m[i] * out.rate / E) / E * k[i].x;
    }
  }
  if (!second_order) return out;
  // u_i'' = A_ui q'' − b_ui (the dot rows of k_i·e); g'' = Σ w_i u_i'' + (Σ_{m_i>0} u_i'² − g'²)/E
  double turning = 0.0;
  for (int i = 0; i < axes; ++i) {
    if (w[i] == 0.0) continue;
    out.A += w[i] * (k[i].x.transpose() * e.J + e.x.transpose() * k[i].J);
    out.b -= w[i] * (e.g.dot(k[i].x) + 2.0 * e.v.dot(k[i].v) + e.x.dot(k[i].g));
    if (m[i] > 0.0) turning += ud[i] * ud[i];
  }
  if (!out.inside) out.b -= (turning - out.rate * out.rate) / E;
  return out;
}

void JointModel::violation(const Eigen::Ref<const VectorXd>& q,
                           const Eigen::Ref<const VectorXd>& qd, double t,
                           ConstraintScratch* scratch, Eigen::Ref<VectorXd> position,
                           Eigen::Ref<VectorXd> velocity) const {
  PoseCache* const cache = cache_of(scratch);
  if (planar_revolute_) {
    // phi = (x_C + R_C s_C − x_P − R_P s_P)_xy,  phi' = Σ ± (x' + theta' e_z × R s)_xy
    // (summed in locals, in the same order, then stored)
    double p0 = 0.0, p1 = 0.0, v0 = 0.0, v1 = 0.0;
    const VecExpr& d = rows_[0].a;
    for (int side = 0; side < 2; ++side) {
      const BodyRef& body = slots_[std::size_t(side == 0 ? d.slot_b : d.slot_a)];
      const double sign = side == 0 ? 1.0 : -1.0;
      const PlanarPoint p = planar_point(body, q, qd, side == 0 ? d.s_b : d.s_a, cache);
      p0 += sign * p.rx;
      p1 += sign * p.ry;
      if (body.ground()) continue;
      const Index o = body.offset;
      p0 += sign * q[o];
      p1 += sign * q[o + 1];
      v0 += sign * (qd[o] - p.w * p.ry);
      v1 += sign * (qd[o + 1] + p.w * p.rx);
    }
    position[0] = p0;
    position[1] = p1;
    velocity[0] = v0;
    velocity[1] = v1;
    return;
  }
  general_violation(q, qd, t, cache, position, velocity);
}

void JointModel::general_violation(const Eigen::Ref<const VectorXd>& q,
                                   const Eigen::Ref<const VectorXd>& qd, double t, PoseCache* cache,
                                   Eigen::Ref<VectorXd> position,
                                   Eigen::Ref<VectorXd> velocity) const {
  // positions and velocities only (every use is preceded by eval)
  VecKin ka{VecKin::Unset{}}, kb{VecKin::Unset{}};
  for (std::size_t r = 0; r < rows_.size(); ++r) {
    const Row& row = rows_[r];
    const Index i = Index(r);
    const Vector3d c = row.c.at(t);
    switch (row.kind) {
      case Row::kDot:
        if (!reuses_a_[r]) eval(row.a, q, qd, cache, ka, false);
        eval(row.b, q, qd, cache, kb, false);
        position[i] = ka.x.dot(kb.x) - c[0];
        velocity[i] = ka.v.dot(kb.x) + ka.x.dot(kb.v) - c[1];
        break;
      case Row::kDistance:
        if (!reuses_a_[r]) eval(row.a, q, qd, cache, ka, false);
        position[i] = (ka.x.squaredNorm() - row.length * row.length) * (0.5 / row.length);
        velocity[i] = ka.x.dot(ka.v) / row.length;
        break;
      case Row::kNorm: {
        // phi = σ (|a| − L),  phi' = σ a·v_a / |a|
        if (!reuses_a_[r]) eval(row.a, q, qd, cache, ka, false);
        const double len = ka.x.norm();
        position[i] = row.sign * (len - row.length);
        velocity[i] = row.sign * ka.x.dot(ka.v) / len;
        break;
      }
      case Row::kLinear:
        position[i] = -c[0];
        velocity[i] = -c[1];
        for (const auto& [z, coef] : row.terms) {
          position[i] += coef * q[z];
          velocity[i] += coef * qd[z];
        }
        break;
      case Row::kDisk: {
        // phi = n·d − r h,  phi' = [n·d]' + r s s' / h
        VecKin ku{VecKin::Unset{}};
        eval(row.a, q, qd, cache, ka, false);
        eval(row.b, q, qd, cache, kb, false);
        eval(row.axis, q, qd, cache, ku, false);
        const double s = kb.x.dot(ku.x);
        const double h = std::sqrt(std::max(1.0 - s * s, 0.0));
        position[i] = ka.x.dot(kb.x) - row.length * h;
        velocity[i] = ka.v.dot(kb.x) + ka.x.dot(kb.v) +
                      row.length * s * (kb.v.dot(ku.x) + kb.x.dot(ku.v)) / h;
        break;
      }
      case Row::kDiskSphere: {
        eval(row.a, q, qd, cache, ka, false);
        eval(row.axis, q, qd, cache, kb, false);
        const DiskSphereGap d = disk_sphere_gap(ka, kb, row.length, row.sphere, false);
        position[i] = d.g;
        velocity[i] = d.rate;
        break;
      }
      case Row::kSphereBox: {
        VecKin axes[3] = {VecKin{VecKin::Unset{}}, VecKin{VecKin::Unset{}},
                          VecKin{VecKin::Unset{}}};
        eval(row.a, q, qd, cache, ka, false);
        for (int z = 0; z < row.box_axes; ++z) eval(row.box[z], q, qd, cache, axes[z], false);
        const SphereBoxGap d = sphere_box_gap(ka, axes, row.box_axes, row.half, row.length, false);
        position[i] = d.g;
        velocity[i] = d.rate;
        break;
      }
    }
  }
}
// ---- quaternion mass matrix and velocity terms ---------------------------------------------

void quaternion_mass(const Vector4d& u, const Vector3d& J, Eigen::Ref<MatrixXd> Mk) {
  // M = 4 E_vᵀ J E_v (rank 3, singular along u)
  const Matrix34 Ev = E_v(u);
  Mk = 4.0 * (Ev.transpose() * J.asDiagonal() * Ev);
}

Vector4d quaternion_velocity_force(const Vector4d& u, const Vector4d& ud, const Vector3d& J) {
  // Q_u = −8 E_v(u')ᵀ J E_v(u) u'   (docs/multibody.md, eq. Q)
  const Vector3d Jw = J.asDiagonal() * (E_v(u) * ud);
  return -8.0 * E_v(ud).transpose() * Jw;
}

void add_point_force(const BodyRef& b, const Eigen::Ref<const VectorXd>& q, const Vector3d& s,
                     const Vector3d& F, Eigen::Ref<VectorXd> Q, PoseCache* cache) {
  if (b.ground()) return;
  const Index o = b.offset;
  switch (b.kind) {
    case BodyKind::kParticle:
      Q.segment<3>(o) += F;
      break;
    case BodyKind::kPlanar: {
      const CosSin cs = planar_cos_sin(cache, b, q[o + 2]);
      const double c = cs.c, sn = cs.s;
      const double rx = c * s.x() - sn * s.y(), ry = sn * s.x() + c * s.y();
      Q[o] += F.x();
      Q[o + 1] += F.y();
      Q[o + 2] += rx * F.y() - ry * F.x();
      break;
    }
    case BodyKind::kRigid:
      Q.segment<3>(o) += F;
      Q.segment<4>(o + 3) += rotate_jacobian(q.segment<4>(o + 3), s).transpose() * F;
      break;
  }
}

void add_torque(const BodyRef& b, const Eigen::Ref<const VectorXd>& q, const Vector3d& tau,
                Eigen::Ref<VectorXd> Q) {
  if (b.ground()) return;
  const Index o = b.offset;
  if (b.kind == BodyKind::kPlanar) {
    Q[o + 2] += tau.z();
  } else if (b.kind == BodyKind::kRigid) {
    // virtual power tauᵀ ω_W = tauᵀ 2 G_v u'
    Q.segment<4>(o + 3) += 2.0 * G_v(q.segment<4>(o + 3)).transpose() * tau;
  }
}

Vector3d angular_velocity_W(const BodyRef& b, const Eigen::Ref<const VectorXd>& q,
                            const Eigen::Ref<const VectorXd>& qd) {
  if (b.ground() || b.kind == BodyKind::kParticle) return Vector3d::Zero();
  const Index o = b.offset;
  if (b.kind == BodyKind::kPlanar) return {0.0, 0.0, qd[o + 2]};
  const Vector4d u = q.segment<4>(o + 3);
  return 2.0 * G_v(u) * qd.segment<4>(o + 3) / u.squaredNorm();
}

Matrix3d rotation_WB(const BodyRef& b, const Eigen::Ref<const VectorXd>& q, PoseCache* cache) {
  if (b.ground() || b.kind == BodyKind::kParticle) return Matrix3d::Identity();
  if (cache != nullptr) return cache->rotation(b, q);
  const Index o = b.offset;
  if (b.kind == BodyKind::kPlanar) {
    return Eigen::AngleAxisd(q[o + 2], Vector3d::UnitZ()).toRotationMatrix();
  }
  const Vector4d u = q.segment<4>(o + 3);
  return Quaterniond(u[0], u[1], u[2], u[3]).normalized().toRotationMatrix();
}

}  // namespace ukdyn::mb::detail
