#include "server/app/cli.h"

int main(int argc, char** argv) { return sage::server::RunCli(argc, argv); }
