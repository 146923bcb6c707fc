#include "cli/study_output.hpp"

#include "cli/commands.hpp"

#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>

#include "probecomp/io/charts.hpp"
#include "probecomp/io/format.hpp"
#include "probecomp/io/output_files.hpp"

namespace probecomp::cli::study {

using io::fmt;

namespace {

// The sections of index.html, in this order: the studies' (kStudyNames), the free-form noise sweep after freeform.
std::vector<std::string> section_order() {
  std::vector<std::string> order;
  for (const std::string& name : kStudyNames) {
    order.push_back(name);
    if (name == "freeform") order.push_back("freeform-noise");
  }
  return order;
}

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in) throw std::runtime_error("cannot read " + path.string());
  return text.str();
}

// The page: the sections in section_order(), `name`'s from `section` (about to be written), the others as DIR holds
// them. Everything inline (style, figures): the page opens offline and references nothing.
std::string index_html(const std::filesystem::path& dir, const std::string& name, const std::string& section) {
  std::string sections;
  std::vector<std::string> present;
  for (const std::string& n : section_order()) {
    const std::filesystem::path file = dir / (n + ".section.html");
    if (n == name) {
      sections += section;
    } else if (std::filesystem::is_regular_file(file)) {
      sections += read_text(file);
    } else {
      continue;
    }
    present.push_back(n);
  }
  std::string list;
  for (std::size_t k = 0; k < present.size(); ++k) {
    list += (k == 0 ? "" : k + 1 == present.size() ? " and " : ", ") + std::string("<code>") + io::xml_escape(present[k]) +
            "</code>";
  }
  return "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
         "<title>probecomp: the paper's studies</title>\n<style>\n"
         "body { font-family: \"DejaVu Sans\", Arial, sans-serif; color: #222; max-width: 1180px; margin: 1.5em auto; "
         "padding: 0 1em; line-height: 1.4; }\n"
         "section { border-top: 1px solid #ccc; margin-top: 2em; }\n"
         "figure { margin: 1em 0; overflow-x: auto; }\n"
         "table { border-collapse: collapse; margin: 1em 0; font-size: 14px; }\n"
         "th, td { border: 1px solid #ccc; padding: 3px 8px; text-align: right; font-variant-numeric: tabular-nums; }\n"
         "th:first-child, td:first-child { text-align: left; }\n"
         "tr.paper td { color: #555; font-style: italic; }\n"
         "</style>\n</head>\n<body>\n<h1>probecomp: the paper's studies</h1>\n"
         "<p>Ristic, Ainsworth and Brujic, <i>Proc IMechE B</i> 215 (2001): the studies run by <code>probecomp study NAME "
         "--output-dir</code> into this directory (" +
         list +
         "), our numbers beside the paper's. Each study's series and summary are also in NAME.csv and NAME.json, its "
         "figures in NAME*.svg. Hover over a marker or a bar for its value.</p>\n" +
         sections + "</body>\n</html>\n";
}

}  // namespace

// NAME.csv, NAME.json, the figures, NAME.section.html and index.html, all or none.
void write_study_files(const std::string& dir, const std::string& name, const StudyFiles& out) {
  if (dir.empty()) return;
  std::filesystem::create_directories(dir);
  const std::filesystem::path d(dir);
  io::OutputFiles files;
  files.add(d / (name + ".csv"), out.csv);
  files.add(d / (name + ".json"), out.json);
  std::string figures;
  for (const auto& [file, svg] : out.figures) {
    files.add(d / file, svg);
    figures += ", " + file;
  }
  files.add(d / (name + ".section.html"), out.section);
  files.add(d / "index.html", index_html(d, name, out.section));
  files.commit();
  std::cout << "Wrote " << (d / (name + ".csv")).string() << " (the series), " << name << ".json (the summary)" << figures
            << ", " << name << ".section.html and index.html (the sections of every study in " << dir << ").\n";
}

std::string html_table(const std::vector<std::string>& header, const std::vector<TableRow>& rows) {
  std::string t = "<table>\n<tr>";
  for (const std::string& h : header) t += "<th>" + io::xml_escape(h) + "</th>";
  t += "</tr>\n";
  for (const TableRow& row : rows) {
    t += row.paper ? "<tr class=\"paper\">" : "<tr>";
    for (const std::string& c : row.cells) t += "<td>" + io::xml_escape(c) + "</td>";
    t += "</tr>\n";
  }
  return t + "</table>\n";
}
std::string html_section(const std::string& id, const std::string& heading, const std::string& paragraph_html,
                         const std::vector<std::string>& svgs, const std::string& rest_html) {
  std::string s = "<section id=\"" + io::xml_escape(id) + "\">\n<h2>" + io::xml_escape(heading) + "</h2>\n<p>" +
                  paragraph_html + "</p>\n";
  for (const std::string& svg : svgs) s += "<figure>\n" + svg + "</figure>\n";
  return s + rest_html + "</section>\n";
}
// The paper's numbers as the paper prints them (0.0014, 16.7), ours as our JSON does.
std::string paper_number(double v) { return fmt("%g", v); }

// Lengths in the studies' JSON to 1e-9 mm, as in their CSV.
io::Json length(double mm) { return io::json_fixed(mm, 9); }
// A figure given to a few significant digits (a noise level, a peak, a ratio: %g).
io::Json figure(double v) { return io::json_number(v, 6); }
// A share (a coverage) to 1e-4, as in the studies' CSV.
io::Json share(double v) { return io::json_fixed(v, 4); }

io::Json json_summary(const studies::ErrorSummary& s) {
  return {{"points", s.points}, {"std", length(s.std)}, {"mean", length(s.mean)}, {"min", length(s.min)},
          {"max", length(s.max)}};
}

}  // namespace probecomp::cli::study
