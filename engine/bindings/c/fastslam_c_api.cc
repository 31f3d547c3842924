// Landmark FastSLAM's C entry points (grove/c_api.h) over the generic layer (c_handle.h): its
// configuration's C members, its inputs (controls, scans) and read-outs (landmarks, pose
// covariance, summary).
#include <string>
#include <type_traits>
#include <vector>

#include "engine/bindings/c/c_handle.h"
#include "grove/c_api.h"
#include "grove/fastslam.h"

namespace grove::capi {
namespace {

static_assert(GROVE_FASTSLAM_FILTER_FASTSLAM1 == static_cast<int>(FastSlamFilter::kFastSlam1));
static_assert(GROVE_FASTSLAM_FILTER_FASTSLAM2 == static_cast<int>(FastSlamFilter::kFastSlam2));
static_assert(GROVE_FASTSLAM_FILTER_UNSCENTED == static_cast<int>(FastSlamFilter::kUnscented));
static_assert(GROVE_FASTSLAM_FILTER_SRCD == static_cast<int>(FastSlamFilter::kSrcd));
static_assert(GROVE_FASTSLAM_FILTER_SRCD_AIDED == static_cast<int>(FastSlamFilter::kSrcdAided));
static_assert(GROVE_FASTSLAM_FILTER_SRCD_PARTICLE ==
              static_cast<int>(FastSlamFilter::kSrcdParticle));
static_assert(GROVE_FASTSLAM_FILTER_DE_SRCD == static_cast<int>(FastSlamFilter::kDeSrcd));
static_assert(GROVE_FASTSLAM_VEHICLE_BAILEY == static_cast<int>(FastSlamVehicle::kBailey));
static_assert(GROVE_FASTSLAM_VEHICLE_GUIVANT_NEBOT ==
              static_cast<int>(FastSlamVehicle::kGuivantNebot));
static_assert(GROVE_FASTSLAM_ASSOCIATION_KNOWN == static_cast<int>(FastSlamAssociation::kKnown));
static_assert(GROVE_FASTSLAM_ASSOCIATION_MAXIMUM_LIKELIHOOD ==
              static_cast<int>(FastSlamAssociation::kMaximumLikelihood));
static_assert(GROVE_FASTSLAM_ASSOCIATION_EXCLUSIVE ==
              static_cast<int>(FastSlamAssociation::kExclusive));
static_assert(GROVE_FASTSLAM_ASSOCIATION_SAMPLED ==
              static_cast<int>(FastSlamAssociation::kSampled));
static_assert(GROVE_FASTSLAM_ASSOCIATION_JCBB ==
              static_cast<int>(FastSlamAssociation::kJointCompatibility));
static_assert(GROVE_FASTSLAM_GATE_DISTANCE2 == static_cast<int>(FastSlamGateUnit::kDistance2));
static_assert(GROVE_FASTSLAM_GATE_PROBABILITY == static_cast<int>(FastSlamGateUnit::kProbability));
static_assert(GROVE_FASTSLAM_EVIDENCE_OFF == static_cast<int>(FastSlamEvidence::kOff));
static_assert(GROVE_FASTSLAM_EVIDENCE_ON == static_cast<int>(FastSlamEvidence::kOn));
// The enumerations' underlying types are int (fixed), so every int the C struct holds is a
// value of the enum; Validate() refuses the ones outside the named choices.
static_assert(std::is_same_v<std::underlying_type_t<FastSlamFilter>, int>);

const ConfigBinding<FastSlamConfig, grove_fastslam_config>& Binding() {
  using C = grove_fastslam_config;
  return BindOnce<FastSlamConfig, C>(FastSlamConfigFields(), [] {
    return std::vector<std::vector<CMember<C>>>{FilterMembers<C>(),
                                                {GROVE_C_MEMBER(C, filter),
                                                 GROVE_C_MEMBER(C, vehicle),
                                                 GROVE_C_MEMBER(C, wheelbase_m),
                                                 GROVE_C_MEMBER(C, encoder_offset_m),
                                                 GROVE_C_MEMBER(C, laser_forward_m),
                                                 GROVE_C_MEMBER(C, laser_left_m),
                                                 GROVE_C_MEMBER(C, sigma_speed_mps),
                                                 GROVE_C_MEMBER(C, sigma_steer_rad),
                                                 GROVE_C_MEMBER(C, sigma_range_m),
                                                 GROVE_C_MEMBER(C, sigma_bearing_rad),
                                                 GROVE_C_MEMBER(C, start_x_m),
                                                 GROVE_C_MEMBER(C, start_y_m),
                                                 GROVE_C_MEMBER(C, start_heading_rad),
                                                 GROVE_C_MEMBER(C, ut_alpha),
                                                 GROVE_C_MEMBER(C, ut_beta),
                                                 GROVE_C_MEMBER(C, ut_kappa),
                                                 GROVE_C_MEMBER(C, cd_step),
                                                 GROVE_C_MEMBER(C, de_scale),
                                                 GROVE_C_MEMBER(C, de_crossover),
                                                 GROVE_C_MEMBER(C, de_generations),
                                                 GROVE_C_MEMBER(C, association),
                                                 GROVE_C_MEMBER(C, reject_gate),
                                                 GROVE_C_MEMBER(C, augment_gate),
                                                 GROVE_C_MEMBER(C, gate_unit),
                                                 GROVE_C_MEMBER(C, evidence),
                                                 GROVE_C_MEMBER(C, evidence_threshold),
                                                 GROVE_C_MEMBER(C, sensor_range_m),
                                                 GROVE_C_MEMBER(C, sensor_fov_rad),
                                                 GROVE_C_MEMBER(C, index_cell_m)}};
  });
}

grove_landmark_estimate LandmarkToC(const LandmarkEstimate& e) {
  return grove_landmark_estimate{e.id, e.x_m, e.y_m, e.sxx, e.sxy, e.syy, e.source_id};
}

grove_fastslam_summary SummaryToC(const FastSlamSummary& s) {
  grove_fastslam_summary out{};
  out.filter = FilterSummaryToC(s);
  out.controls = s.controls;
  out.scans = s.scans;
  out.observations = s.observations;
  out.predict_steps = s.predict_steps;
  out.landmarks = s.landmarks;
  out.associated = s.association.associated;
  out.created = s.association.created;
  out.ignored = s.association.ignored;
  out.removed = s.association.removed;
  out.dropped = s.association.dropped;
  out.tagged = s.association.tagged;
  out.wrong = s.association.wrong;
  out.truncated = s.association.truncated;
  out.evolution_trials = s.evolution.trials;
  out.evolution_accepted = s.evolution.accepted;
  out.map_memory = MemoryToC(s.map_memory);
  out.trajectory_memory = MemoryToC(s.trajectory_memory);
  return out;
}

}  // namespace
}  // namespace grove::capi

struct grove_fastslam : grove::capi::Handle<grove::FastSlam> {};

namespace capi = grove::capi;

GROVE_C_MODEL_ENTRY_POINTS(grove_fastslam, capi::Binding(), capi::SummaryToC)
using grove::FastSlam;

grove_status grove_fastslam_control(grove_fastslam* slam, double t_s, double speed_mps,
                                    double steer_rad) {
  return capi::Stepping(slam, [&](FastSlam& e) { return e.Control(t_s, speed_mps, steer_rad); });
}

grove_status grove_fastslam_scan(grove_fastslam* slam, double t_s,
                                 const grove_landmark_observation* obs, size_t n) {
  if (slam != nullptr && obs == nullptr && n != 0) {
    return capi::Guard(slam, [&] {
      return slam->Fail(GROVE_INVALID_ARGUMENT,
                        std::string(__func__) + ": obs is NULL with n = " + std::to_string(n));
    });
  }
  return capi::Stepping(slam, [&](FastSlam& e) {
    std::vector<grove::LandmarkObservation> z(n);
    for (size_t i = 0; i < n; ++i) z[i] = {obs[i].range_m, obs[i].bearing_rad, obs[i].id};
    return e.Scan(t_s, z);
  });
}

grove_status grove_fastslam_pose_covariance(grove_fastslam* slam,
                                            grove_pose_covariance* covariance) {
  return capi::Get(slam, __func__, covariance, "covariance", [](FastSlam& e) {
    const grove::Pose2Covariance c = e.PoseCovariance();
    return grove_pose_covariance{c.xx, c.xy, c.xh, c.yy, c.yh, c.hh};
  });
}

grove_status grove_fastslam_heaviest_trajectory(grove_fastslam* slam, grove_pose* out,
                                                size_t capacity, size_t* count) {
  return capi::Trajectory(slam, __func__, out, capacity, count, &FastSlam::HeaviestTrajectory);
}

grove_status grove_fastslam_landmarks(grove_fastslam* slam, grove_landmark_estimate* out,
                                      size_t capacity, size_t* count) {
  return capi::ReadOut(
      slam, __func__, out, capacity, count, [](FastSlam& e) { return e.HeaviestLandmarks(); },
      capi::LandmarkToC);
}
