#pragma once
// `sage view`: the live view's page over a recorded mission, finished or partial. The page asks
// for the frame at any mission time (its slider, or play at a chosen pace) and gets what the
// live page would have shown then: every vehicle where the record last saw it (greyed when
// lost, gone or not heard lately), its trail, each valve's risk from the profile and the risk
// events so far, its visits and last visit counted from every row, the events so far and the
// metric. Nothing can be acted on.
#include <map>
#include <memory>
#include <mutex>

#include "server/live/live_frame.h"
#include "server/live/view_server.h"
#include "server/report/run_record.h"

namespace sage::live {

class Replay final : public ViewSource {
 public:
  explicit Replay(server::RunRecord record, double trail_s = 4.0, int trail_points = 8);

  /// The frame at mission time t (clamped to the record).
  LiveFrame FrameAt(double t) const;
  const LiveScene& scene() const { return scene_; }
  const server::RunRecord& record() const { return record_; }

  std::string SceneJson() const override;
  std::shared_ptr<const std::string> NextFrame(std::uint64_t, bool, std::chrono::milliseconds, std::uint64_t*) override {
    return nullptr;
  }
  std::string FrameJson(std::optional<double> t) override;
  std::string HeatJson(std::optional<double> t) override;
  ActionAnswer Act(const ActionRequest& request) override;
  bool live() const override { return false; }

 private:
  // The valves' raw weights after the first `events` risk events.
  std::vector<double> WeightsAfter(std::size_t events) const;
  std::size_t RiskEventsBy(double t) const;

  server::RunRecord record_;
  LiveScene scene_;
  double trail_s_;
  int trail_points_;
  double stale_after_s_;
  std::vector<int> ids_;                                     // [vehicle index] -> fleet id
  std::vector<std::vector<std::pair<double, VehicleStatus>>> status_changes_;  // [vehicle index]
  std::vector<EventView> events_;                            // fleet and risk events in time order
  std::vector<double> initial_weights_;
  mutable std::mutex heat_mutex_;
  mutable std::map<std::size_t, std::string> heat_cache_;    // risk events applied -> heat JSON
};

}  // namespace sage::live
