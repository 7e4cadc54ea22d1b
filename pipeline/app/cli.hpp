// The glaswave command line (PRODUCT.md section 2): parses arguments, runs the command, and
// turns errors into one `glaswave: error:` line and the contract's exit status.
#pragma once

namespace glaswave {

int run_command_line(int argc, char** argv);

}  // namespace glaswave
