// The charts of a run outside a mission's run directory (sage evaluate --out): the same six
// files RunDirectory::Finish writes, each replaced atomically.
#include <filesystem>

#include "server/report/atomic_write.h"
#include "server/report/report.h"

namespace sage::server {

void WritePlots(const std::string& dir, const plots::MissionPlotInput& input) {
  for (const plots::PlotFile& f : plots::MissionPlotFiles(input)) {
    detail::WriteAtomically((std::filesystem::path(dir) / f.name).string(), f.bytes);
  }
}

}  // namespace sage::server
