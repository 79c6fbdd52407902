// SPDX-License-Identifier: BSD-3-Clause
// System and SystemBuilder: validation and freezing of a description.
#include "ukdyn/core/system.hpp"

#include <limits>

#include "dynamics/internal.hpp"
#include "ukdyn/core/autodiff.hpp"
#include "ukdyn/core/format.hpp"

#include <algorithm>
#include <atomic>
#include <set>
#include <stdexcept>
#include <utility>

namespace ukdyn {

namespace {
std::uint64_t next_system_id() {
  static std::atomic<std::uint64_t> counter{0};
  return ++counter;
}

std::string join_names(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& s : names) out += (out.empty() ? "'" : ", '") + s + "'";
  return out.empty() ? "(none)" : out;
}
}  // namespace

Index System::constraint_index(std::string_view name) const {
  for (std::size_t k = 0; k < constraints_.size(); ++k) {
    if (constraints_[k].name() == name) return Index(k);
  }
  // (the contacts' stick constraints are internal: not listed)
  std::vector<std::string> names;
  for (std::size_t k = 0; k < user_constraints_ && k < constraints_.size(); ++k) {
    names.push_back(constraints_[k].name());
  }
  throw std::invalid_argument("ukdyn::System: no constraint named '" + std::string(name) +
                              "'; the constraints are " + join_names(names));
}

Index System::coordinate_index(std::string_view name) const {
  for (std::size_t i = 0; i < names_.size(); ++i) {
    if (names_[i] == name) return Index(i);
  }
  // the other spelling of a body's coordinate: crank_x for crank.x (and back), when exactly one
  // coordinate matches with every '.' read as '_'
  const auto key = [](std::string_view s) {
    std::string k(s);
    std::replace(k.begin(), k.end(), '.', '_');
    return k;
  };
  const std::string wanted = key(name);
  Index found = -1;
  for (std::size_t i = 0; i < names_.size(); ++i) {
    if (key(names_[i]) != wanted) continue;
    if (found >= 0) {
      found = -1;
      break;
    }
    found = Index(i);
  }
  if (found >= 0) return found;
  throw std::invalid_argument("ukdyn::System: no coordinate named '" + std::string(name) +
                              "'; the coordinates are " + join_names(names_));
}

SystemBuilder::SystemBuilder(Index n) : n_(n) {
  if (n <= 0) {
    throw std::invalid_argument(
        "ukdyn::SystemBuilder: the number of coordinates must be "
        "positive, got " +
        format_number(n));
  }
  for (Index i = 0; i < n; ++i) names_.push_back(std::string("q").append(format_number(i)));
}

SystemBuilder::SystemBuilder(std::vector<std::string> coordinate_names)
    : n_(Index(coordinate_names.size())), names_(std::move(coordinate_names)) {
  if (n_ == 0) throw std::invalid_argument("ukdyn::SystemBuilder: no coordinates given");
  std::set<std::string> seen;
  for (const auto& s : names_) {
    if (s.empty()) throw std::invalid_argument("ukdyn::SystemBuilder: empty coordinate name");
    if (!seen.insert(s).second) {
      throw std::invalid_argument("ukdyn::SystemBuilder: coordinate '" + s + "' named twice");
    }
  }
}

SystemBuilder& SystemBuilder::scratch(ScratchFactory factory) {
  scratch_ = std::move(factory);
  return *this;
}

// A callable without scratch is wrapped into one that ignores it (an empty one stays empty).
SystemBuilder& SystemBuilder::mass_matrix(MassMatrixFn fn) {
  mass_ = nullptr;
  if (fn) {
    mass_ = [f = std::move(fn)](const Eigen::Ref<const VectorXd>& q, double t, CallableScratch*,
                                Eigen::Ref<MatrixXd> M) { f(q, t, M); };
  }
  has_constant_mass_ = false;
  return *this;
}

SystemBuilder& SystemBuilder::mass_matrix(MassMatrixScratchFn fn) {
  mass_ = std::move(fn);
  has_constant_mass_ = false;
  return *this;
}

SystemBuilder& SystemBuilder::mass_matrix(const Eigen::Ref<const MatrixXd>& M) {
  if (M.rows() != n_ || M.cols() != n_) {
    throw std::invalid_argument("ukdyn::SystemBuilder::mass_matrix: expected a " +
                                format_number(n_) + "x" + format_number(n_) + " matrix, got " +
                                format_number(M.rows()) + "x" + format_number(M.cols()));
  }
  mass_constant_ = M;
  has_constant_mass_ = true;
  // the closure owns its copy of M (the argument is a view, gone after this call)
  mass_ = [M = mass_constant_](const Eigen::Ref<const VectorXd>&, double, CallableScratch*,
                               Eigen::Ref<MatrixXd> out) { out = M; };
  return *this;
}

SystemBuilder& SystemBuilder::mass_block(Index offset, const Eigen::Ref<const MatrixXd>& Mkk) {
  if (Mkk.rows() != Mkk.cols() || Mkk.rows() == 0) {
    throw std::invalid_argument(
        "ukdyn::SystemBuilder::mass_block: expected a non-empty square "
        "block, got " +
        format_number(Mkk.rows()) + "x" + format_number(Mkk.cols()));
  }
  mass_blocks_.push_back(MassBlock{offset, Mkk.rows(), {}, Mkk});
  return *this;
}

SystemBuilder& SystemBuilder::mass_block(Index offset, Index size, MassBlockFn fn) {
  if (size <= 0 || !fn) {
    throw std::invalid_argument("ukdyn::SystemBuilder::mass_block: need size > 0 and a callable");
  }
  mass_blocks_.push_back(MassBlock{offset, size, std::move(fn), {}});
  return *this;
}

SystemBuilder& SystemBuilder::singular_mass_block(Index offset, Index size, MassBlockFn fn) {
  if (size <= 0 || !fn) {
    throw std::invalid_argument(
        "ukdyn::SystemBuilder::singular_mass_block: need size > 0 and a callable");
  }
  mass_blocks_.push_back(MassBlock{offset, size, std::move(fn), {}, /*singular=*/true});
  return *this;
}

SystemBuilder& SystemBuilder::forces(ForceFn fn) {
  forces_ = nullptr;
  if (fn) {
    forces_ = [f = std::move(fn)](const Eigen::Ref<const VectorXd>& q,
                                  const Eigen::Ref<const VectorXd>& qd, double t, CallableScratch*,
                                  Eigen::Ref<VectorXd> Q) { f(q, qd, t, Q); };
  }
  return *this;
}

SystemBuilder& SystemBuilder::forces(ForceScratchFn fn) {
  forces_ = std::move(fn);
  return *this;
}

SystemBuilder& SystemBuilder::potential_energy(PotentialFn fn) {
  potential_ = nullptr;
  if (fn) {
    potential_ = [f = std::move(fn)](const Eigen::Ref<const VectorXd>& q, double t,
                                     CallableScratch*) { return f(q, t); };
  }
  return *this;
}

SystemBuilder& SystemBuilder::potential_energy(PotentialScratchFn fn) {
  potential_ = std::move(fn);
  return *this;
}

SystemBuilder& SystemBuilder::external_power(PowerFn fn) {
  external_power_ = nullptr;
  if (fn) {
    external_power_ = [f = std::move(fn)](const Eigen::Ref<const VectorXd>& q,
                                          const Eigen::Ref<const VectorXd>& qd, double t,
                                          CallableScratch*) { return f(q, qd, t); };
  }
  return *this;
}

SystemBuilder& SystemBuilder::external_power(PowerScratchFn fn) {
  external_power_ = std::move(fn);
  return *this;
}

SystemBuilder& SystemBuilder::mass_tree(std::vector<Index> parent) {
  mass_tree_ = std::move(parent);
  return *this;
}

SystemBuilder& SystemBuilder::accounts_for_energy(bool accounts) {
  accounts_for_energy_ = accounts;
  return *this;
}

SystemBuilder& SystemBuilder::switching_functions(std::vector<std::string> names,
                                                  SwitchScratchFn fn) {
  switch_names_ = fn ? std::move(names) : std::vector<std::string>();
  switches_ = std::move(fn);
  return *this;
}

SystemBuilder& SystemBuilder::add(Constraint c) {
  constraints_.push_back(std::move(c));
  return *this;
}

SystemBuilder& SystemBuilder::add(NonIdealForce f) {
  nonideal_.push_back(std::move(f));
  return *this;
}

System SystemBuilder::build() const {
  if (!mass_ && mass_blocks_.empty()) {
    throw std::invalid_argument(
        "ukdyn::SystemBuilder::build: no mass matrix was given "
        "(call mass_matrix(fn), mass_matrix(M) or mass_block(...))");
  }
  if (mass_ && !mass_blocks_.empty()) {
    throw std::invalid_argument(
        "ukdyn::SystemBuilder::build: give either mass_matrix or "
        "mass_block, not both");
  }
  // the mass tree: a parent before each coordinate (or none)
  if (!mass_tree_.empty() && Index(mass_tree_.size()) != n_) {
    throw std::invalid_argument("ukdyn::SystemBuilder::build: mass_tree gives " +
                                format_number(Index(mass_tree_.size())) +
                                " parents, the system has " + format_number(n_) + " coordinates");
  }
  for (std::size_t k = 0; k < mass_tree_.size(); ++k) {
    if (mass_tree_[k] < -1 || mass_tree_[k] >= Index(k)) {
      throw std::invalid_argument("ukdyn::SystemBuilder::build: mass_tree gives coordinate " +
                                  format_number(Index(k)) + " the parent " +
                                  format_number(mass_tree_[k]) +
                                  "; it must be -1 (a root) or a coordinate before it");
    }
  }
  System s;
  s.n_ = n_;
  s.names_ = names_;
  s.mass_ = mass_;
  s.mass_tree_ = mass_tree_;
  s.mass_constant_ = has_constant_mass_;
  if (!mass_blocks_.empty()) {
    // blocks tile [0, n): sorted by offset, each starting where the previous one ended
    std::vector<MassBlock> blocks = mass_blocks_;
    std::sort(blocks.begin(), blocks.end(),
              [](const MassBlock& a, const MassBlock& b) { return a.offset < b.offset; });
    Index next = 0;
    bool constant = true;
    for (const MassBlock& b : blocks) {
      if (b.offset != next) {
        throw std::invalid_argument(
            "ukdyn::SystemBuilder::build: mass blocks must tile the coordinates: " +
            (b.offset < next
                 ? "the block at offset " + format_number(b.offset) + " overlaps the one before it"
                 : "coordinates " + format_number(next) + " to " + format_number(b.offset - 1) +
                       " have no mass block"));
      }
      next = b.offset + b.size;
      constant = constant && b.constant();
    }
    if (next != n_) {
      throw std::invalid_argument("ukdyn::SystemBuilder::build: mass blocks cover " +
                                  format_number(next) + " coordinates, the system has " +
                                  format_number(n_));
    }
    s.mass_blocks_ = blocks;
    s.mass_constant_ = constant;
    s.mass_ = [blocks](const Eigen::Ref<const VectorXd>& q, double t, CallableScratch*,
                       Eigen::Ref<MatrixXd> M) {
      M.setZero();
      for (const MassBlock& b : blocks) {
        auto Mk = M.block(b.offset, b.offset, b.size, b.size);
        if (b.constant()) {
          Mk = b.value;
        } else {
          b.fn(q, t, Mk);
        }
      }
    };
  }
  s.forces_ =
      forces_
          ? forces_
          : ForceScratchFn([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&,
                              double, CallableScratch*, Eigen::Ref<VectorXd> Q) { Q.setZero(); });
  s.scratch_ = scratch_;
  // each Coulomb contact brings its stick constraint P (v − u) = 0, inactive unless switched on
  std::vector<Constraint> all = constraints_;
  for (const auto& f : nonideal_) {
    const CoulombFriction* spec = f.coulomb();
    if (spec == nullptr) continue;
    if (spec->kinematics) {
      // the contact-point path: T q' = 0 (its columns are checked with the other constraints',
      // its tangents when the force is bound)
      if (spec->kinematics.tangents < 1 || spec->kinematics.tangents > 2) {
        throw std::invalid_argument("ukdyn::coulomb_friction '" + f.name() +
                                    "': the contact kinematics' tangents must be 1 or 2, got " +
                                    format_number(spec->kinematics.tangents));
      }
      const Constraint* normal = nullptr;
      for (const auto& c : constraints_) {
        if (c.name() == spec->constraint) normal = &c;
      }
      Constraint stick =
          detail::point_stick_constraint("stick." + f.name(), spec->kinematics, normal);
      const double never = std::numeric_limits<double>::infinity();
      stick.active_between(never, never);
      all.push_back(stick);
      continue;
    }
    std::vector<Index> coords = spec->coordinates;
    if (coords.empty()) {
      for (Index i = 0; i < n_; ++i) coords.push_back(i);
    }
    for (Index i : coords) {
      if (i < 0 || i >= n_) {
        throw std::invalid_argument("ukdyn::coulomb_friction '" + f.name() +
                                    "': coordinate index " + format_number(i) +
                                    " is out of range [0, " + format_number(n_) + ")");
      }
    }
    // its normal constraint, by name (binding below reports one that does not exist)
    const Constraint* normal = nullptr;
    for (const auto& c : constraints_) {
      if (c.name() == spec->constraint) normal = &c;
    }
    Constraint stick =
        detail::stick_constraint("stick." + f.name(), coords, spec->surface_velocity, normal);
    const double never = std::numeric_limits<double>::infinity();
    stick.active_between(never, never);
    all.push_back(stick);
  }
  std::set<std::string> seen;
  for (const auto& c : all) {
    if (!seen.insert(c.name()).second) {
      throw std::invalid_argument("ukdyn::SystemBuilder::build: constraint '" + c.name() +
                                  "' is declared twice");
    }
    const std::vector<Index>& cols = c.model().columns();
    for (std::size_t j = 0; j < cols.size(); ++j) {
      if (cols[j] < 0 || cols[j] >= n_ || (j > 0 && cols[j] <= cols[j - 1])) {
        throw std::invalid_argument("ukdyn::SystemBuilder::build: constraint '" + c.name() +
                                    "': columns() must be strictly increasing coordinate "
                                    "indices in [0, " +
                                    format_number(n_) + ")");
      }
    }
    s.offsets_.push_back(s.m_);
    s.m_ += c.rows();
  }
  s.potential_ = potential_;
  s.external_power_ = external_power_;
  s.switch_names_ = switch_names_;
  s.switches_ = switches_;
  s.accounts_for_energy_ = accounts_for_energy_ || potential_ || external_power_ || !forces_;
  s.constraints_ = all;
  s.user_constraints_ = constraints_.size();
  s.id_ = next_system_id();
  // bind the non-ideal forces last: they may look up constraints and coordinates by name
  std::set<std::string> seen_forces;
  for (const auto& f : nonideal_) {
    if (!seen_forces.insert(f.name()).second) {
      throw std::invalid_argument("ukdyn::SystemBuilder::build: non-ideal force '" + f.name() +
                                  "' is declared twice");
    }
    s.nonideal_names_.push_back(f.name());
    s.nonideal_fns_.push_back(f.bind(s));
    if (const CoulombFriction* spec = f.coulomb()) {
      FrictionContact contact;
      contact.force = Index(s.nonideal_fns_.size()) - 1;
      contact.normal_constraint = s.constraint_index(spec->constraint);
      contact.stick_constraint = s.constraint_index("stick." + f.name());
      contact.coordinates = spec->coordinates;
      contact.normal_coordinates = spec->normal_coordinates;
      contact.kinematics = spec->kinematics;
      if (contact.coordinates.empty() && !contact.kinematics) {
        for (Index i = 0; i < n_; ++i) contact.coordinates.push_back(i);
      }
      contact.mu = spec->mu;
      contact.mu_static = spec->mu_static.value_or(spec->mu);
      contact.eps = spec->regularization_velocity;
      contact.surface_velocity = spec->surface_velocity;
      s.contacts_.push_back(contact);
    }
  }
  return s;
}

}  // namespace ukdyn
