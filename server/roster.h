#pragma once
// Who is in a mission: every vehicle the server has heard of, when it joined, whether it is
// alive, lost or has left, its index in the run's record (the trajectory's vehicle column, in
// order of joining), and the ids the server issues to vehicles added at runtime. Every change
// is an event for the record (fleet_events.csv).
#include <cstdint>
#include <map>
#include <string>
#include <unordered_set>
#include <vector>

#include <Eigen/Core>

#include "agents/fleet_messages.h"
#include "server/id_index.h"

namespace sage::server {

/// A change of the fleet, as fleet_events.csv records it.
struct FleetEventRecord {
  double time_s = 0.0;
  std::string what;     ///< joined, rejoined, lost, left, outage, resumed, empty
  int vehicle_id = -1;  ///< -1 for events of the whole mission (outage, empty)
  std::string name;
  std::string detail;
};

class Roster {
 public:
  enum class Status { kAlive, kLost, kLeft };
  struct Member {
    int id = 0;
    std::string name;
    int index = 0;                    ///< the record's vehicle index, in order of first joining
    Status status = Status::kAlive;
    double joined_s = 0.0;            ///< latest (re)join
    int joins = 0;                    ///< how many times it (re)joined this server (not checkpointed)
    double gone_s = 0.0;              ///< when it was lost or left (if it is)
    bool has_state = false;
    agents::StateReport last;         ///< its latest state (position, command, target cycle)
    std::int64_t recorded_cycle = -1; ///< the latest of its cycles in the record
    bool target_sent = false;         ///< its assignment went out since it (re)joined
  };

  /// first_free_id: the first id the server may issue (after the scenario's vehicles and joins).
  explicit Roster(int first_free_id = 0) : next_id_(first_free_id) {}
  Roster(const Roster&) = delete;  // Find's index points into members_
  Roster& operator=(const Roster&) = delete;

  /// Vehicle `id` was heard of (its first state, or again after it was gone). Returns the event
  /// to record, or nullptr if it was already alive.
  const FleetEventRecord* Join(int id, const std::string& name, double time_s);
  /// It was lost (its liveliness lapsed) or left cleanly. Returns the event to record, or
  /// nullptr if it was not alive.
  const FleetEventRecord* Leave(int id, bool lost, double time_s);

  Member* Find(int id);
  const Member* Find(int id) const;
  /// Whether some member (alive or gone) goes by `name`.
  bool NameTaken(const std::string& name) const { return names_taken_.count(name) != 0; }
  /// Ascending ids, kept between changes of who is in (a 10,000-vehicle fleet walked its map of
  /// members for them every cycle).
  const std::vector<int>& alive() const;
  /// Each member's name by its record index (valid until the next Join or Restore).
  const std::vector<const std::string*>& names_by_index() const;

  /// A member as the live view shows it. The glances sit in one compact array in ascending id,
  /// kept as states arrive (Heard), so that a frame copies it instead of walking the members:
  /// at 1,000 vehicles that walk, cold after the cycle's own work, took 0.13-0.19 ms of the
  /// server's loop a frame.
  struct Glance {
    int id = 0;
    Status status = Status::kAlive;
    bool has_state = false;
    float x_m = 0.0f, y_m = 0.0f, heading_rad = 0.0f;  ///< of its latest state
    double heard_s = 0.0;                               ///< mission time of its latest state
    std::string name;
  };
  /// Every member's glance, ascending id (valid until the next Join, Leave or Restore).
  const std::vector<Glance>& glances() const;
  /// m's latest state (m.last, m.has_state) changed: its glance follows.
  void Heard(const Member& m);
  std::size_t alive_count() const { return alive_count_; }
  std::size_t lost_count() const { return lost_count_; }
  const std::map<int, Member>& members() const { return members_; }

  /// Reserves `count` fresh ids for vehicles added at runtime; returns the first.
  int ReserveIds(int count);
  int next_id() const { return next_id_; }
  /// The id the server next issues is at least `id` (ids a host chose itself stay unique).
  void ReserveUpTo(int id);

  /// A whole-mission event (outage, resumed, empty): the roster keeps the latest for the record.
  const FleetEventRecord* Note(double time_s, std::string what, std::string detail);

  /// Plain data of a checkpoint.
  struct State {
    std::map<int, Member> members;
    int next_id = 0;
    std::size_t lost_count = 0;
  };
  State Checkpoint() const { return {members_, next_id_, lost_count_}; }
  void Restore(State state);

 private:
  std::map<int, Member> members_;
  IdIndex<Member> by_id_;  // Find's (a 10,000-vehicle cycle looked each vehicle up several times)
  std::unordered_set<std::string> names_taken_;
  int next_id_ = 0;
  std::size_t alive_count_ = 0;
  std::size_t lost_count_ = 0;
  FleetEventRecord event_;
  // Derived from members_, made again on first use after a change.
  mutable std::vector<int> alive_;
  mutable std::vector<const std::string*> names_;
  mutable std::vector<Glance> glances_;
  mutable std::vector<std::size_t> glance_of_index_;  // a member's record index -> its glance
  mutable bool alive_stale_ = true, names_stale_ = true, glances_stale_ = true;
};

}  // namespace sage::server
