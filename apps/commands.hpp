// One function per subcommand, each in its own cmd_*.cpp; main.cpp lists them.
#pragma once

#include <CLI/CLI.hpp>

namespace clutterseg::app {

void add_segment_command(CLI::App& app);
void add_eval_command(CLI::App& app);
void add_bench_command(CLI::App& app);

}  // namespace clutterseg::app
