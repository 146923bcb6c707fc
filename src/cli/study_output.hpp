#pragma once
// What every `probecomp study NAME` writes (DESIGN.md §3): NAME.csv (the series), NAME.json (the summary), its
// figures as SVG, NAME.section.html and index.html (the sections of every study in the directory), all or none;
// and the HTML and JSON pieces the studies' sections share.

#include <string>
#include <utility>
#include <vector>

#include "probecomp/io/json.hpp"
#include "probecomp/studies/comparison.hpp"

namespace probecomp::cli::study {

// What a study writes: NAME.csv, NAME.json, its figures (file name in DIR, SVG text) and its section of index.html.
struct StudyFiles {
  std::string csv{}, json{};
  std::vector<std::pair<std::string, std::string>> figures{};
  std::string section{};
};

void write_study_files(const std::string& dir, const std::string& name, const StudyFiles& out);

// HTML pieces of the sections. Cells are escaped; a row with `paper` set is the paper's (shown apart).
struct TableRow {
  std::vector<std::string> cells{};
  bool paper = false;
};
[[nodiscard]] std::string html_table(const std::vector<std::string>& header, const std::vector<TableRow>& rows);
[[nodiscard]] std::string html_section(const std::string& id, const std::string& heading,
                                       const std::string& paragraph_html, const std::vector<std::string>& svgs,
                                       const std::string& rest_html);
// The paper's numbers as the paper prints them (0.0014, 16.7), ours as our JSON does.
[[nodiscard]] std::string paper_number(double v);
// Lengths in the studies' JSON to 1e-9 mm, as in their CSV.
[[nodiscard]] io::Json length(double mm);
// A figure given to a few significant digits (a noise level, a peak, a ratio: %g).
[[nodiscard]] io::Json figure(double v);
// A share (a coverage) to 1e-4, as in the studies' CSV.
[[nodiscard]] io::Json share(double v);
[[nodiscard]] io::Json json_summary(const studies::ErrorSummary& s);

}  // namespace probecomp::cli::study
