// The glaswave command.
#include "pipeline/app/cli.hpp"

int main(int argc, char** argv) { return glaswave::run_command_line(argc, argv); }
