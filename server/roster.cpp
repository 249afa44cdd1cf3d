#include "server/roster.h"

#include <algorithm>
#include <stdexcept>

#include <fmt/format.h>

namespace sage::server {

const FleetEventRecord* Roster::Join(int id, const std::string& name, double time_s) {
  auto [it, first] = members_.try_emplace(id);
  Member& m = it->second;
  if (!first && m.status == Status::kAlive) return nullptr;
  const bool rejoined = !first;
  if (first) {
    m.id = id;
    m.index = static_cast<int>(members_.size()) - 1;
    ReserveUpTo(id + 1);
    by_id_.Add(id, m);
  }
  if (rejoined && m.status == Status::kLost && lost_count_ > 0) --lost_count_;
  if (rejoined && m.name != name) names_taken_.erase(m.name);  // names are unique: it was its own
  m.name = name;
  names_taken_.insert(m.name);
  m.status = Status::kAlive;
  alive_stale_ = names_stale_ = glances_stale_ = true;
  m.joined_s = time_s;
  ++m.joins;
  m.target_sent = false;
  ++alive_count_;
  event_ = {time_s, rejoined ? "rejoined" : "joined", id, name, ""};
  return &event_;
}

const FleetEventRecord* Roster::Leave(int id, bool lost, double time_s) {
  Member* m = Find(id);
  if (m == nullptr || m->status != Status::kAlive) return nullptr;
  m->status = lost ? Status::kLost : Status::kLeft;
  alive_stale_ = glances_stale_ = true;
  m->gone_s = time_s;
  --alive_count_;
  if (lost) ++lost_count_;
  const std::string detail =
      m->has_state ? fmt::format("last heard at t = {:.1f} s", m->last.time_s) : std::string("never heard");
  event_ = {time_s, lost ? "lost" : "left", id, m->name, detail};
  return &event_;
}

Roster::Member* Roster::Find(int id) { return by_id_.Find(members_, id); }

const Roster::Member* Roster::Find(int id) const { return by_id_.Find(members_, id); }

const std::vector<int>& Roster::alive() const {
  if (alive_stale_) {
    alive_.clear();
    alive_.reserve(alive_count_);
    for (const auto& [id, m] : members_)
      if (m.status == Status::kAlive) alive_.push_back(id);
    alive_stale_ = false;
  }
  return alive_;
}

const std::vector<const std::string*>& Roster::names_by_index() const {
  if (names_stale_) {
    names_.assign(members_.size(), nullptr);
    for (const auto& [id, m] : members_) names_[m.index] = &m.name;
    names_stale_ = false;
  }
  return names_;
}

namespace {

void Glimpse(const Roster::Member& m, Roster::Glance& g) {
  g.has_state = m.has_state;
  g.x_m = static_cast<float>(m.last.state.position_m.x());
  g.y_m = static_cast<float>(m.last.state.position_m.y());
  g.heading_rad = static_cast<float>(m.last.state.heading_rad);
  g.heard_s = m.last.time_s;
}

}  // namespace

const std::vector<Roster::Glance>& Roster::glances() const {
  if (glances_stale_) {
    glances_.resize(members_.size());
    glance_of_index_.resize(members_.size());
    std::size_t k = 0;
    for (const auto& [id, m] : members_) {
      Glance& g = glances_[k];
      g.id = id;
      g.status = m.status;
      g.name = m.name;
      Glimpse(m, g);
      glance_of_index_[static_cast<std::size_t>(m.index)] = k++;
    }
    glances_stale_ = false;
  }
  return glances_;
}

void Roster::Heard(const Member& m) {
  if (!glances_stale_) Glimpse(m, glances_[glance_of_index_[static_cast<std::size_t>(m.index)]]);
}

int Roster::ReserveIds(int count) {
  if (count < 1) throw std::invalid_argument("Roster::ReserveIds: count must be >= 1");
  const int first = next_id_;
  next_id_ += count;
  return first;
}

void Roster::ReserveUpTo(int id) { next_id_ = std::max(next_id_, id); }

const FleetEventRecord* Roster::Note(double time_s, std::string what, std::string detail) {
  event_ = {time_s, std::move(what), -1, "", std::move(detail)};
  return &event_;
}

void Roster::Restore(State state) {
  members_ = std::move(state.members);
  by_id_.Rebuild(members_);
  names_taken_.clear();
  for (const auto& [id, m] : members_) names_taken_.insert(m.name);
  next_id_ = state.next_id;
  lost_count_ = state.lost_count;
  alive_count_ = 0;
  for (const auto& [id, m] : members_) alive_count_ += m.status == Status::kAlive ? 1 : 0;
  alive_stale_ = names_stale_ = glances_stale_ = true;
}

}  // namespace sage::server
