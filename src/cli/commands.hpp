#pragma once
// The end-to-end commands (DESIGN.md §5): compensate, fit and demo. Each returns the exit status and throws
// std::exception with a one-line message for bad input; output files are written whole or not at all.

#include <string>

namespace probecomp::cli {

struct CompensateArgs {
  std::string cad, points, output, json, report, method = "cad";
  double probe_radius = 0.0;
  bool quiet = false;
};
int run_compensate(const CompensateArgs& args);

struct FitArgs {
  std::string cad, points, output, json;
  double probe_radius = 0.0;
  bool quiet = false;
};
int run_fit(const FitArgs& args);

struct DemoArgs {
  std::string output_dir = "probecomp-demo";
  bool quiet = false;
};
int run_demo(const DemoArgs& args);

}  // namespace probecomp::cli
