#pragma once
// `sage run`, `sage compare` and `sage evaluate`: missions in-process (the same mission core and
// agent objects a DDS launch runs, in lockstep) and the metrics of a recorded trajectory.
#include "server/app/options.h"

namespace sage::server {

int CmdRun(const RunCommand& command);
int CmdCompare(const RunCommand& command);
int CmdEvaluate(const EvaluateCommand& command);

}  // namespace sage::server
