#pragma once
// `sage view RUNDIR`: the live view's page over a finished or partial mission's run directory,
// with a time slider and play/pause, served on 127.0.0.1 until Ctrl-C.
#include "server/app/options.h"

namespace sage::server {

int CmdView(const ViewCommand& command);

}  // namespace sage::server
