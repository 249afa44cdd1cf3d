#pragma once
// The QoS of each SAGE Fleet stream, in one place so that server, vehicles and operator tools
// cannot disagree (DDS silently refuses to match a reader whose requested QoS is stronger than
// the writer's offered QoS). Pass the same function's result to both the writer and the reader,
// except VehicleState, whose liveliness lease is offered by writers only.
#include <chrono>
#include <memory>

struct dds_qos;  // from dds/dds.h; kept opaque so this header stays light

namespace sage::proto {

/// Liveliness lease a vehicle offers on VehicleState (ms): a vehicle silent for this long is
/// reported NOT_ALIVE_NO_WRITERS. Measured here: kill -9 detected after ~0.5 s with 500 ms.
inline constexpr std::chrono::milliseconds kDefaultVehicleLease{500};

/// How long a reliable writer may block when a reader's history is full (ms) before
/// dds_write fails with TIMEOUT.
inline constexpr std::chrono::milliseconds kMaxBlockingTime{100};

/// Owns one dds_qos_t (dds_delete_qos on destruction). Move-only.
class Qos {
 public:
  /// A fresh, empty QoS (every policy at its DDS default).
  Qos();
  /// The owned QoS, for dds_create_writer / dds_create_reader and dds_qset_*.
  dds_qos* get() const noexcept { return qos_.get(); }

 private:
  struct Deleter {
    void operator()(dds_qos* qos) const noexcept;
  };
  std::unique_ptr<dds_qos, Deleter> qos_;
};

/// VehicleState writer (vehicles): best-effort, keep-last 1, AUTOMATIC liveliness with `lease`,
/// writer autodispose off. `lease` must be > 0.
Qos VehicleStateWriterQos(std::chrono::milliseconds lease = kDefaultVehicleLease);

/// VehicleState reader (server, viewers): best-effort, keep-last 1 per vehicle, and requests
/// AUTOMATIC liveliness with an infinite lease so it matches writers of any lease.
Qos VehicleStateReaderQos();

/// VehicleState reader of the mission's record (the server): as VehicleStateReaderQos but
/// keep-last `depth` per vehicle, so the states a stalled server could not take meanwhile are
/// still there when it wakes (best-effort: as many as the socket buffer held).
Qos VehicleStateRecordQos(int depth = 256);

/// VehicleState reader of an agent host (the other hosts' vehicles it keeps apart from): as
/// VehicleStateRecordQos(depth), but the states its own participant writes are not delivered to
/// it. The host knows its own vehicles; a host of 7,500 took and dropped 75,000 of its own
/// samples a second.
Qos NeighbourStateQos(int depth);

/// VehicleCoverage (vehicles -> server): reliable, keep-last 1 per vehicle, volatile.
Qos VehicleCoverageQos();

/// ErgodicTarget (server -> vehicles): reliable, transient-local, keep-last 1 per vehicle.
Qos ErgodicTargetQos();

/// ErgodicTargets (server -> vehicles, a cycle's changed assignments in one sample): reliable,
/// volatile, keep-last kErgodicTargetsDepth. Each sample carries changes no later one repeats, so
/// a reader keeps the unread ones of 64 cycles; one missed all the same (a reader matched late, a
/// host further behind) is found from the vehicle's states and sent again alone
/// (server/node/server_door.h).
inline constexpr int32_t kErgodicTargetsDepth = 64;
Qos ErgodicTargetsQos();

/// FleetCoverage (server -> vehicles, once a cycle): reliable, volatile, keep-last 1 — only the
/// newest accounting matters, and the next cycle brings one to a late joiner within 0.1 s.
Qos FleetCoverageQos();

/// RiskUpdate (operators/sensors -> server, viewers), keyed by source: reliable, transient-local,
/// keep-last 16 per source.
Qos RiskUpdateQos();

/// RiskUpdateResult (server -> the operator who sent the update): reliable, transient-local, keep-last 256.
Qos RiskUpdateResultQos();

/// MissionStatus (server -> everyone): reliable, transient-local, keep-last 1.
Qos MissionStatusQos();

/// FleetCommand (operators -> server, server -> hosts): reliable, volatile, keep-all.
Qos FleetCommandQos();

/// FleetCommandResult (server -> the operator who sent the command): reliable, transient-local,
/// keep-last 256, like RiskUpdateResult.
Qos FleetCommandResultQos();

/// Detection (vehicles' sensor scans -> server), keyed by vehicle: reliable, volatile, keep-last
/// 32 per vehicle.
Qos DetectionQos();

}  // namespace sage::proto
