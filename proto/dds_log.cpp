#include "proto/dds_log.h"

#include <atomic>
#include <cctype>
#include <cstdio>
#include <mutex>
#include <set>

#include <dds/dds.h>

namespace sage::proto {
namespace {

std::string_view Trimmed(std::string_view text) {
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.front()))) text.remove_prefix(1);
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.remove_suffix(1);
  return text;
}

// The message with every run of hex digits and ':' or '.' between them as '#': GUIDs, addresses,
// ports and times out, the words kept.
std::string KindOf(std::string_view text) {
  std::string kind;
  bool in_number = false;
  for (const char c : text) {
    const bool hex = std::isxdigit(static_cast<unsigned char>(c)) != 0;
    // A word's own letters a-f stay: only digits start a number, which then takes hex letters,
    // ':' and '.' along.
    const bool starts = std::isdigit(static_cast<unsigned char>(c)) != 0;
    if (in_number && (hex || c == ':' || c == '.')) continue;
    in_number = starts;
    kind += starts ? '#' : c;
  }
  return kind;
}

std::atomic<int> g_starting{0};  // participants of this process being made (ParticipantStartup)
constexpr const char* kRefusedKind = "secure participant refused";

std::mutex g_told_mutex;
std::set<std::string>* g_told = nullptr;  // kinds told in this process (never freed: Cyclone may log at exit)

extern "C" void TellDdsLog(void*, const dds_log_data_t* data) {
  if (data == nullptr || data->message == nullptr) return;
  // `message` is the text alone: Cyclone's header (time, domain, thread) sits before it.
  std::string kind;
  const std::string line = DdsLogLine(std::string_view(data->message, data->size), &kind);
  if (line.empty()) return;
  if (kind == kRefusedKind && g_starting.load() > 0) return;  // the startup race: not told, nor marked told
  {
    std::lock_guard lock(g_told_mutex);
    if (!g_told->insert(kind).second) return;
  }
  std::fprintf(stderr, "%s\n", line.c_str());
}

}  // namespace

std::string DdsLogLine(std::string_view text, std::string* kind) {
  text = Trimmed(text);
  if (kind != nullptr) kind->clear();
  if (text.empty()) return "";
  if (text.find("Remote secure participant") != std::string_view::npos && text.find("not allowed") != std::string_view::npos) {
    // Cyclone refused a secured participant that none of this process's participants accepts:
    // one of the mission's processes closing its participant while the others still announce, or
    // another mission's or tool's credentials on this domain. Nothing of the mission is lost.
    if (kind != nullptr) *kind = kRefusedKind;
    return "sage: dds: a secured participant on this DDS domain was refused (one this process's credentials do not "
           "accept: a process of the mission closing, or another mission's or tool's); nothing of the mission is lost";
  }
  if (kind != nullptr) *kind = KindOf(text);
  return "sage: dds: " + std::string(text);
}

ParticipantStartup::ParticipantStartup() { ++g_starting; }
ParticipantStartup::~ParticipantStartup() { --g_starting; }

void RouteDdsLog() {
  static std::once_flag once;
  std::call_once(once, [] {
    g_told = new std::set<std::string>();
    dds_set_log_sink(TellDdsLog, nullptr);
  });
}

}  // namespace sage::proto
