#pragma once
#include <array>

/// Topic names of the SAGE Fleet DDS streams, ROS 2 style ("rt/" prefix) so ros2 topic list sees them.
namespace sage::proto {
inline constexpr const char* kVehicleStateTopic = "rt/sage/vehicle_state";
inline constexpr const char* kVehicleCoverageTopic = "rt/sage/vehicle_coverage";
inline constexpr const char* kErgodicTargetTopic = "rt/sage/ergodic_target";
inline constexpr const char* kErgodicTargetsTopic = "rt/sage/ergodic_targets";
inline constexpr const char* kFleetCoverageTopic = "rt/sage/fleet_coverage";
inline constexpr const char* kRiskUpdateTopic = "rt/sage/risk_update";
inline constexpr const char* kRiskUpdateResultTopic = "rt/sage/risk_update_result";
inline constexpr const char* kMissionStatusTopic = "rt/sage/mission_status";
inline constexpr const char* kFleetCommandTopic = "rt/sage/fleet_command";
inline constexpr const char* kFleetCommandResultTopic = "rt/sage/fleet_command_result";
inline constexpr const char* kDetectionTopic = "rt/sage/detection";

/// Every topic of a mission: DDS Security's governance and permissions are derived from this list
/// (proto/access_policy.h), so a topic added here without an access rule fails their tests.
inline constexpr std::array<const char*, 11> kMissionTopics = {
    kVehicleStateTopic,   kVehicleCoverageTopic, kErgodicTargetTopic,      kErgodicTargetsTopic,
    kFleetCoverageTopic,  kRiskUpdateTopic,      kRiskUpdateResultTopic,   kMissionStatusTopic,
    kFleetCommandTopic,   kFleetCommandResultTopic, kDetectionTopic,
};
}  // namespace sage::proto
