// probecomp command-line tool. Subcommands arrive with later work (info, project, compensate, demo, ...).

#include <CLI/CLI.hpp>
#include <iostream>

#include "version.hpp"

int main(int argc, char** argv) {
  CLI::App app{
      "probecomp: CAD-based contact-probe radius compensation for CMM data.\n"
      "Turns raw probe-centre points into contact points and deviations using the part's NURBS model.",
      "probecomp"};
  app.set_version_flag("--version", std::string("probecomp ") + probecomp::kVersion);
  app.require_subcommand(0, 1);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  if (app.get_subcommands().empty()) {
    std::cout << app.help();
  }
  return 0;
}
