// Neighbour vehicle trajectories (the ego's route translated, or a route of
// their own) and the vehicle body-box blockage test.
#include "tools/sim/coop.hpp"

#include <cmath>

namespace uwbnav::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

}  // namespace

void NeighbourTracks::build(const Scenario& s, double end_s) {
  vehicles_ = s.coop.vehicles;
  tracks_.assign(vehicles_.size(), Trajectory{});
  const double heading_rad = s.route.start_heading_deg * kDeg;
  for (size_t i = 0; i < vehicles_.size(); ++i) {
    const NeighbourDef& n = vehicles_[i];
    Scenario own = s;
    own.coop.vehicles.clear();
    if (n.motion == NeighbourMotion::kOffset) {
      // Same maneuvers from a translated start: the whole trajectory is translated.
      own.route.start_nav_m[0] += std::cos(heading_rad) * n.offset_m[0] - std::sin(heading_rad) * n.offset_m[1];
      own.route.start_nav_m[1] += std::sin(heading_rad) * n.offset_m[0] + std::cos(heading_rad) * n.offset_m[1];
    } else {
      own.route = n.route;
      own.route.kind = RouteKind::kVehicle;
      own.route.loop_from = n.route.maneuvers.empty() ? 0 : n.route.maneuvers.size() - 1;
    }
    tracks_[i].build(own, end_s);
  }
}

Eigen::Vector3d NeighbourTracks::tag_nav_m(size_t i, uint64_t t_us) const {
  const KinState st = at(i, t_us);
  const double* l = vehicles_[i].tag_lever_body_m;
  return st.pos_nav_m + st.R_nav_body * Eigen::Vector3d(l[0], l[1], l[2]);
}

bool segment_hits_vehicle(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const KinState& body,
                          const double box_m[3]) {
  // In the vehicle's body frame the box is axis-aligned.
  const Eigen::Matrix3d Rt = body.R_nav_body.transpose();
  const Eigen::Vector3d pb = Rt * (p - body.pos_nav_m);
  const Eigen::Vector3d qb = Rt * (q - body.pos_nav_m);
  Box b;
  b.min_nav_m[0] = -0.5 * box_m[0];
  b.max_nav_m[0] = 0.5 * box_m[0];
  b.min_nav_m[1] = -0.5 * box_m[1];
  b.max_nav_m[1] = 0.5 * box_m[1];
  b.min_nav_m[2] = 0.0;
  b.max_nav_m[2] = box_m[2];
  return segment_hits_box(pb, qb, b);
}

}  // namespace uwbnav::sim
