#pragma once
// Cyclone DDS's own log lines (its warnings and errors: discovery, security, the network) told in
// the mission's words on stderr, each kind once a process, rather than raw on a launch's terminal
// ("1796572609.373001 [142] dq.builtin: Remote secure participant ab7fdb26:...: not allowed" had
// reached new users' screens mid-mission with nothing to say what it meant).
#include <string>
#include <string_view>

namespace sage::proto {

/// What a Cyclone log message (its text after Cyclone's own header) is told as: one line starting
/// "sage: dds: ", or empty for nothing to say. `kind` (may be null) gets the message with its
/// numbers and identifiers taken out, so that a kind is told once however many participants,
/// ports or times it names.
std::string DdsLogLine(std::string_view text, std::string* kind);

/// While one lives (this process making a participant), Cyclone's refusals of secured
/// participants are not told: a launch's server, made at the same moment as its agent hosts, had
/// refused a host's participant it heard while its own was still being set up, and accepted it a
/// moment later (the mission ran whole), yet "a secured participant ... was refused" had reached
/// the terminal in launches begun within seconds of another. A refusal after it is told as before.
class ParticipantStartup {
 public:
  ParticipantStartup();
  ~ParticipantStartup();
  ParticipantStartup(const ParticipantStartup&) = delete;
  ParticipantStartup& operator=(const ParticipantStartup&) = delete;
};

/// Routes Cyclone's log (its info, warnings and errors; traces stay off) through DdsLogLine to
/// stderr, each kind once a process. Called before the first participant; idempotent.
void RouteDdsLog();

}  // namespace sage::proto
