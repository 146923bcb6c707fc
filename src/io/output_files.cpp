#include "probecomp/io/output_files.hpp"

#include <cerrno>
#include <fstream>
#include <stdexcept>
#include <system_error>

#include "probecomp/error.hpp"

namespace probecomp::io {

namespace {

// OUT.csv → OUT.partial.csv beside it: the extension kept for writers that choose the format by it.
std::filesystem::path temporary_for(const std::filesystem::path& destination) {
  std::filesystem::path t = destination;
  t.replace_filename(destination.stem().string() + ".partial" + destination.extension().string());
  return t;
}

// The same file: equal once made absolute and normalised (symbolic links resolved where they exist), or, when
// both exist, the same file on disk (hard links).
bool same_file(const std::filesystem::path& a, const std::filesystem::path& b) {
  std::error_code ec;
  if (std::filesystem::exists(a, ec) && std::filesystem::exists(b, ec)) {
    const bool eq = std::filesystem::equivalent(a, b, ec);
    if (!ec) return eq;
  }
  const std::filesystem::path ca = std::filesystem::weakly_canonical(a, ec);
  if (ec) return a.lexically_normal() == b.lexically_normal();
  const std::filesystem::path cb = std::filesystem::weakly_canonical(b, ec);
  if (ec) return a.lexically_normal() == b.lexically_normal();
  return ca == cb;
}

}  // namespace

void check_outputs_spare_inputs(const std::vector<NamedPath>& outputs, const std::vector<NamedPath>& inputs) {
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const NamedPath& out = outputs[i];
    if (out.path.empty()) continue;
    for (const NamedPath& in : inputs) {
      if (!in.path.empty() && same_file(out.path, in.path)) {
        throw std::invalid_argument(out.option + " " + out.path.string() + " is the " + in.option +
                                    " file: an input is never overwritten; choose another output name");
      }
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (!outputs[j].path.empty() && same_file(out.path, outputs[j].path)) {
        throw std::invalid_argument(out.option + " and " + outputs[j].option + " name the same file, " +
                                    out.path.string());
      }
    }
  }
}

OutputFiles::~OutputFiles() {
  std::error_code ec;
  for (const Staged& s : staged_) std::filesystem::remove(s.temporary, ec);
}

void OutputFiles::add(const std::filesystem::path& destination, const std::string& text) {
  add_streamed(destination, [&](std::ostream& out) { out << text; });
}

void OutputFiles::add_streamed(const std::filesystem::path& destination, const std::function<void(std::ostream&)>& write) {
  add(destination, [&](const std::filesystem::path& temporary) {
    // errno is what the failing open(2) or write(2) left: the reason a user can act on (no space, read-only).
    const auto cannot = [&] {
      const int reason = errno;
      return InputError(destination.string() + ": cannot be written" + system_reason(reason));
    };
    errno = 0;
    std::ofstream out(temporary, std::ios::binary);
    if (!out) throw cannot();
    write(out);
    out.flush();
    if (!out) throw cannot();
  });
}

void OutputFiles::add(const std::filesystem::path& destination,
                      const std::function<void(const std::filesystem::path&)>& write) {
  const std::filesystem::path temporary = temporary_for(destination);
  // Registered first, so that a failed or interrupted write's remains are removed.
  staged_.push_back({destination, temporary, TemporaryFile(temporary)});
  write(temporary);
}

void OutputFiles::commit() {
  const DeferTermination all_or_none;
  std::error_code ec;
  for (std::size_t k = 0; k < staged_.size(); ++k) {
    std::filesystem::rename(staged_[k].temporary, staged_[k].destination, ec);
    if (ec) {
      const std::string what = staged_[k].destination.string() + ": cannot be written (" + ec.message() + ")" +
                               (k > 0 ? "; the outputs before it were written" : "");
      staged_.erase(staged_.begin(), staged_.begin() + static_cast<std::ptrdiff_t>(k));
      throw InputError(what);
    }
  }
  staged_.clear();
}

}  // namespace probecomp::io
