// clutterseg: model-free segmentation of cluttered depth images (Ückermann et al., IROS 2013).
#include <iostream>

#include "clutterseg/config.hpp"
#include "commands.hpp"
#include "common.hpp"

int main(int argc, char** argv) {
  using namespace clutterseg;
  CLI::App app{"clutterseg: real-time model-free segmentation of cluttered depth images"};
  app.require_subcommand(0, 1);
  bool dump_config = false;
  app.add_flag("--dump-config", dump_config, "print every parameter with its default as JSON and exit");
  app.set_version_flag("--version", "clutterseg 0.1.0");
  app::add_segment_command(app);
  app::add_eval_command(app);
  app::add_bench_command(app);
  try {
    app.parse(argc, argv);
    if (dump_config) {
      std::cout << params_to_json(Params{}) << "\n";
      return 0;
    }
    if (app.get_subcommands().empty()) {
      std::cout << app.help();
      return 2;
    }
  } catch (const CLI::RuntimeError& e) {
    return e.get_exit_code();  // a subcommand finished with this exit code
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const Error& e) {
    app::report_error(e.what());
    return 1;
  } catch (const std::exception& e) {
    app::report_error(std::string("internal error: ") + e.what());
    return 3;
  }
  return 0;
}
