// SPDX-License-Identifier: BSD-3-Clause
// The contacts the viewer draws without `visual: contacts:` (modelfile/visual.hpp,
// VisualContact::geometry): a robot's or a bodies model's `contacts:` entry's point and normal
// at q, and their columns visual.contact.<name>.* at a run's samples.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ukdyn/io/trajectory_files.hpp"
#include "ukdyn/modelfile/visual.hpp"
#include "ukdyn/multibody/multibody.hpp"
#include "ukdyn/multibody/tree.hpp"
#include "ukdyn/multibody/tree_closures.hpp"

namespace ukdyn {

struct Model;

namespace detail {

/// The drawn contact of a robot's contact (tree::contact_constraint, disk_contact_constraint):
/// the point or the centre `at` of a sphere of `radius` (a disk's when `axis`, in at's link
/// frame, is given) and the plane on the world or a link; its geometry runs the forward
/// kinematics of `tree` at q. Cost per call O(links) (it allocates its TreeData).
VisualContact robot_visual_contact(std::string name, std::shared_ptr<const tree::Tree> tree,
                                   const tree::LinkPoint& at, const Eigen::Vector3d* axis,
                                   double radius, const tree::LinkFrame& plane);

/// The drawn contact of a bodies model's contact joint `joint` (mb::contact, mb::contact_disk:
/// the plane is its parent frame's xy plane, z the normal, or its x axis in a planar model,
/// y the normal; the point or centre its child frame's origin, a disk's axis the child frame's
/// z) of `radius`, from the bodies' poses at q. Cost per call O(1).
VisualContact bodies_visual_contact(std::shared_ptr<const mb::MultibodyModel> model,
                                    const mb::JointInfo& joint, double radius);

/// Writes the holding force of each Coulomb friction's stick constraint into its multipliers
/// in traj.lambda (the columns lambda.stick.<friction>[.i]): the stick rows are kappa T (kappa
/// P on the coordinate path), kappa = class(max_i |n_i|) / 10 the unit of the contact's normal
/// rows n_i at the sample (core/coulomb_contact.cpp, normal_row_unit; 1 for a unit normal in SI
/// units, but 1000 for a ball in mm), so the multipliers are the holding force / kappa; × kappa
/// they are the force in the model's force unit along t_1 (t_2) — on the coordinate path the
/// generalized holding force on the sliding coordinates. Applied once to the samples a model
/// run writes (run_model). The multipliers are the whole ones, lambda + lambda_nonideal
/// (Trajectory::lambda), so this is the holding force the slip is decided by. Cost
/// O(samples · contacts · one evaluation of the normal constraint's rows).
void scale_stick_multipliers(const Model& model, Trajectory& traj);

/// The columns visual.contact.<name>.x, .y (, .z), .nx, .ny (, .nz) of every drawn contact with
/// a geometry, at the samples of `traj`, appended to `out` in the order of model.visual.contacts;
/// before them a Coulomb contact's friction: at a contact point .fx, .fy (, .fz) in the world, on
/// the coordinate path .Qf.<coordinate> (the generalized force: the whole stick multiplier while
/// it holds, Qc_nonideal while it slides). Cost O(samples · contacts · links).
void add_contact_columns(const Model& model, const Trajectory& traj, std::vector<CsvColumn>& out);

}  // namespace detail
}  // namespace ukdyn
