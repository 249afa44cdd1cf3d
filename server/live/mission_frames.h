#pragma once
// Frames of a running mission, made from its mission core's public state on the server's own
// loop (a copy of the roster's compact glances and the valves' weights): every vehicle the
// roster knows with its last state, greyed when it has not been heard for a while (stale) or is
// lost or gone; each valve's weight, share, visits and last visit; the clock and the metric.
// Also the event log's lines for the record's events, the same words live and in a replay.
#include "server/live/live_frame.h"
#include "server/mission_core.h"

namespace sage::live {

class MissionFrameMaker {
 public:
  /// scenario: the mission's, outliving the maker.
  explicit MissionFrameMaker(const maps::Scenario& scenario);

  /// The frame as the core stands (events are added by the caller); cycle_ms: the server's
  /// last cycle, finished: the mission has ended.
  LiveFrame Make(const server::MissionCore& core, double cycle_ms, bool finished) const;

  /// A vehicle unheard for longer than this (mission seconds) is shown stale.
  double stale_after_s() const { return stale_after_s_; }

 private:
  const maps::Scenario& scenario_;
  double stale_after_s_;
};

/// The event log's line for a fleet event (joined, lost, left, outage, ...) and a risk change.
EventView EventOf(const server::FleetEventRecord& event);
EventView EventOf(const server::RiskEventRecord& event);

}  // namespace sage::live
