#include "proto/qos.h"

#include <dds/dds.h>

#include <new>
#include <stdexcept>

namespace sage::proto {

namespace {

dds_duration_t ToDuration(std::chrono::milliseconds duration) {
  return DDS_MSECS(duration.count());
}

void SetReliable(const Qos& qos) {
  dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, ToDuration(kMaxBlockingTime));
}

// All keyed SAGE streams are keyed by vehicle_id, so keep-last 1 is "the latest per vehicle":
// without the key it would be the latest of the whole topic (~97 % loss in the design notes).
void SetKeepLast(const Qos& qos, int32_t depth) {
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, depth);
}

// Transient-local with `depth` samples per instance kept for late joiners. Cyclone sizes the
// late-joiner history from the durability_service history (default keep-last 1), not from the
// writer's history: without this a late reader got 1 of 16 risk updates (measured).
void SetTransientLocal(const Qos& qos, int32_t depth) {
  dds_qset_durability(qos.get(), DDS_DURABILITY_TRANSIENT_LOCAL);
  dds_qset_durability_service(qos.get(), 0, DDS_HISTORY_KEEP_LAST, depth, DDS_LENGTH_UNLIMITED,
                              DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED);
}

}  // namespace

Qos::Qos() : qos_(dds_create_qos()) {
  if (!qos_) throw std::bad_alloc();
}

void Qos::Deleter::operator()(dds_qos* qos) const noexcept { dds_delete_qos(qos); }

Qos VehicleStateWriterQos(std::chrono::milliseconds lease) {
  if (lease.count() <= 0) {
    throw std::invalid_argument("VehicleStateWriterQos: lease = " + std::to_string(lease.count()) +
                                " ms: must be > 0");
  }
  Qos qos;
  // Best-effort: a state is superseded 10+ times a second; a retransmitted old pose is useless
  // and reliability would make a slow reader throttle every vehicle.
  dds_qset_reliability(qos.get(), DDS_RELIABILITY_BEST_EFFORT, 0);
  SetKeepLast(qos, 1);
  // AUTOMATIC liveliness: Cyclone asserts it from the participant, so a crashed or killed
  // vehicle process (no goodbye message) is reported NOT_ALIVE_NO_WRITERS after ~lease.
  dds_qset_liveliness(qos.get(), DDS_LIVELINESS_AUTOMATIC, ToDuration(lease));
  // Autodispose off: deleting or losing the writer must read as "no writers" (crash or link
  // loss), while a vehicle that leaves cleanly calls Dispose, read as NOT_ALIVE_DISPOSED.
  dds_qset_writer_data_lifecycle(qos.get(), false);
  return qos;
}

Qos VehicleStateReaderQos() {
  Qos qos;
  dds_qset_reliability(qos.get(), DDS_RELIABILITY_BEST_EFFORT, 0);
  SetKeepLast(qos, 1);
  // A requested lease shorter than a writer's offered lease makes the pair incompatible (no
  // data, no error); requesting "infinite" accepts every vehicle, detection still uses the
  // vehicle's offered lease.
  dds_qset_liveliness(qos.get(), DDS_LIVELINESS_AUTOMATIC, DDS_INFINITY);
  return qos;
}

Qos VehicleStateRecordQos(int depth) {
  if (depth < 1) throw std::invalid_argument("VehicleStateRecordQos: depth must be >= 1");
  Qos qos = VehicleStateReaderQos();
  SetKeepLast(qos, depth);
  return qos;
}

Qos NeighbourStateQos(int depth) {
  Qos qos = VehicleStateRecordQos(depth);
  dds_qset_ignorelocal(qos.get(), DDS_IGNORELOCAL_PARTICIPANT);
  return qos;
}

Qos VehicleCoverageQos() {
  Qos qos;
  // Reliable although each sample supersedes the previous (running sums with seq): a coverage
  // sample carries K^2 doubles (400 -> 3.2 kB, several UDP fragments) and is published at a few
  // Hz, so best-effort would drop the whole sample on one lost fragment and the server would
  // wait a full period. With keep-last 1 the writer only ever repairs the newest sample, so
  // reliability costs no backlog and cannot block a vehicle behind a slow server for long.
  SetReliable(qos);
  SetKeepLast(qos, 1);
  // Volatile: a late server needs only the next sample (sums are cumulative).
  dds_qset_durability(qos.get(), DDS_DURABILITY_VOLATILE);
  return qos;
}

Qos ErgodicTargetQos() {
  Qos qos;
  SetReliable(qos);
  SetKeepLast(qos, 1);
  // Transient-local: a vehicle that joins (or restarts) gets its current target at once from the
  // server's writer history instead of drifting until the next server cycle.
  SetTransientLocal(qos, 1);
  return qos;
}

Qos ErgodicTargetsQos() {
  Qos qos;
  SetReliable(qos);
  SetKeepLast(qos, kErgodicTargetsDepth);
  dds_qset_durability(qos.get(), DDS_DURABILITY_VOLATILE);
  return qos;
}

Qos FleetCoverageQos() {
  Qos qos;
  SetReliable(qos);
  SetKeepLast(qos, 1);
  return qos;
}

Qos RiskUpdateQos() {
  Qos qos;
  SetReliable(qos);
  // Keyed by source: the last 16 changes of each sender, so a late server or viewer replays the
  // recent history of risk changes (weights are absolute, replay order = publication order per
  // sender), and a sender flooding the topic only pushes out its own.
  SetKeepLast(qos, 16);
  SetTransientLocal(qos, 16);
  return qos;
}

Qos FleetCommandResultQos() { return RiskUpdateResultQos(); }

Qos DetectionQos() {
  Qos qos;
  // Reliable: each scan is evidence of its own (a lost scan that saw a leak is a leak seen later),
  // unlike states and coverage, which the next sample supersedes. Keep-last 32 per vehicle: a few
  // seconds of scans at the usual rates, so a server that stalls briefly still gets them, and a
  // vehicle is never held back by a slow server for long.
  SetReliable(qos);
  SetKeepLast(qos, 32);
  dds_qset_durability(qos.get(), DDS_DURABILITY_VOLATILE);
  return qos;
}

Qos RiskUpdateResultQos() {
  Qos qos;
  // Transient-local: the operator's command may be matched by the server's writer a moment after
  // the server took its update and answered; the answer then still reaches it. Answers are
  // matched by the update's stamp, so older ones are ignored. 256 deep: the server answers at
  // most 16 updates of each sender in a cycle (the depth of RiskUpdateQos), so an operator's
  // answer outlives the answers to a dozen flooding senders written in the same cycle (16 deep,
  // one flood's answers pushed an operator's out of the history before it was read).
  SetReliable(qos);
  SetKeepLast(qos, 256);
  SetTransientLocal(qos, 256);
  return qos;
}

Qos MissionStatusQos() {
  Qos qos;
  SetReliable(qos);
  SetKeepLast(qos, 1);
  // Transient-local: a viewer started mid-mission shows the current status immediately.
  SetTransientLocal(qos, 1);
  return qos;
}

Qos FleetCommandQos() {
  Qos qos;
  // Commands are events that must each execute once: reliable and keep-all (no overwrite of
  // an unread "add 5" by a "stop"); volatile so a server started later never replays old orders.
  SetReliable(qos);
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_ALL, 0);
  dds_qset_durability(qos.get(), DDS_DURABILITY_VOLATILE);
  return qos;
}

}  // namespace sage::proto
