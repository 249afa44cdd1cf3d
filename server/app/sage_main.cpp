#include "server/app/cli.h"
#include "server/app/processes.h"

int main(int argc, char** argv) {
  // Its heaps on transparent huge pages (processes.h): at 10,000 vehicles a mission's CPU per
  // vehicle-second fell by 12 % with them (README, Scale). SAGE_HUGE_PAGES=0 starts it as it is.
  sage::server::StartWithHugePages(argv);
  return sage::server::RunCli(argc, argv);
}
