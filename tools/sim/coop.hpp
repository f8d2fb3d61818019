// Neighbour vehicles of a scenario's [coop] section (docs/simulator.md
// "Cooperative ranging"): their truth trajectories at any instant and the
// body-box test that decides whether a third vehicle blocks a range.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "tools/sim/scenario.hpp"
#include "tools/sim/trajectory.hpp"

namespace uwbnav::sim {

// Truth of every neighbour vehicle of a scenario (simulation, evaluation, tests).
class NeighbourTracks {
 public:
  // Builds the trajectories of s.coop.vehicles over [0, end_s]: an offset
  // vehicle drives the ego's route (s.route, a vehicle route) translated by
  // its offset, a route vehicle its own route (repeating its last maneuver).
  void build(const Scenario& s, double end_s);

  size_t size() const { return vehicles_.size(); }
  const NeighbourDef& vehicle(size_t i) const { return vehicles_[i]; }
  // Body origin, attitude and rates of vehicle i at t_us.
  KinState at(size_t i, uint64_t t_us) const { return tracks_[i].at(t_us); }
  // Its ranging tag antenna in the navigation frame at t_us (body origin + R lever).
  Eigen::Vector3d tag_nav_m(size_t i, uint64_t t_us) const;

 private:
  std::vector<NeighbourDef> vehicles_;
  std::vector<Trajectory> tracks_;
};

// True when the segment p->q crosses the body box of a vehicle in pose `body`:
// box_m = length, width, height; centred on the body origin along body x and y,
// from the body origin's plane (the ground) up to the height.
bool segment_hits_vehicle(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const KinState& body,
                          const double box_m[3]);

}  // namespace uwbnav::sim
