#include "probecomp/cad/iges_counts.hpp"

#include <igesread.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

namespace probecomp::cad {

namespace {

// One entity as OpenCASCADE's IGESData_ParamReader reads it: the type from its directory entry, its directory line,
// and its parameters after the type (numbered from 1, as IGES 5.3 numbers them).
struct Entity {
  int type = 0;
  int form = 0;
  int directory_line = 0;
  // IGESData_ParamReader::ReadInteger: an integer parameter as atoi reads it, an empty one as 0; any other fails.
  std::vector<std::optional<int>> integers;

  [[nodiscard]] std::optional<long long> integer(std::size_t i) const {
    if (i < 1 || i > integers.size()) return std::nullopt;
    return integers[i - 1];
  }
  [[nodiscard]] long long count() const { return static_cast<long long>(integers.size()); }
};

// A count is refused when its magnitude exceeds the parameters the entity holds. Magnitude, because OpenCASCADE
// multiplies extents without checking their signs (two negative extents make a positive size); no valid file
// declares a negative count. long double: the products of two 32-bit counts are exact.
class Check {
 public:
  explicit Check(const Entity& e) : e_(e) {}

  // The integer at parameter i, when OpenCASCADE's ReadInteger would succeed on it.
  [[nodiscard]] std::optional<long double> at(std::size_t i) const {
    const std::optional<long long> v = e_.integer(i);
    if (!v) return std::nullopt;
    return static_cast<long double>(*v);
  }

  // Refuse `declared` items of `what` if the entity's parameters cannot hold them (the first refusal stays).
  void need(const char* what, long double declared) {
    if (reason_ || std::fabs(declared) <= static_cast<long double>(e_.count())) return;
    const long double shown = std::clamp(declared, -1e18L, 1e18L);
    reason_ = "IGES entity " + std::to_string(e_.type) + " (directory line " + std::to_string(e_.directory_line) +
              ") declares " + std::to_string(static_cast<long long>(shown)) + " " + what +
              " but its parameter data hold " + std::to_string(e_.count()) + " values";
  }

  [[nodiscard]] std::optional<std::string> reason() && { return std::move(reason_); }

 private:
  const Entity& e_;
  std::optional<std::string> reason_;
};

// A count at a fixed position, or at a position moved on by a list before it (IGESDimen_ToolGeneralSymbol reads NL
// after the NG geometry pointers): checked against the parameters the entity holds.
constexpr int kAnyForm = -1;
struct CountAt {
  int type;
  int form;
  std::size_t at;
  const char* what;
  std::size_t list_count_at = 0;  // where the count of the list before it is, when there is one
  std::size_t list_from = 0;      // where that list starts
};

// OpenCASCADE 7.6.3's ReadOwnParams that make arrays sized by these counts before reading their items (the list
// readers ReadReals, ReadEnts, ... are bounded by PrepareRead first, but a count near 2^31 wraps that bound, so the
// counts of 102 and 106 are here too). One row per site, from IGES{Geom,Solid,Dimen,Draw,Graph,Basic,Appli,Defs}
// Tool*.cxx; IGES 5.3 numbers the parameters after the type from 1.
constexpr CountAt kCounts[] = {
    {102, kAnyForm, 1, "curves"},                        // composite curve: N
    {106, kAnyForm, 2, "points"},                        // copious data (and its centre, section, witness lines): N
    {112, kAnyForm, 4, "segments"},                      // parametric spline curve: N
    {114, kAnyForm, 3, "u segments"},                    // parametric spline surface: M
    {114, kAnyForm, 4, "v segments"},                    //   and N
    {136, kAnyForm, 2, "nodes"},                         // finite element
    {138, kAnyForm, 1, "analysis cases"},                // nodal displacement and rotation: NC
    {138, kAnyForm, 2, "nodes", 1, 2},                   //   NN after NC notes
    {141, kAnyForm, 4, "curves"},                        // boundary
    {143, kAnyForm, 3, "boundaries"},                    // bounded surface
    {144, kAnyForm, 3, "inner boundaries"},              // trimmed surface
    {146, kAnyForm, 4, "values a node"},                 // nodal results: NV
    {146, kAnyForm, 5, "nodes"},                         //   NN
    {148, kAnyForm, 6, "elements"},                      // element results
    {180, kAnyForm, 1, "tree entries"},                  // boolean tree
    {184, kAnyForm, 1, "members"},                       // solid assembly
    {186, kAnyForm, 3, "void shells"},                   // manifold solid B-rep object
    {208, kAnyForm, 6, "leaders"},                       // flag note
    {210, kAnyForm, 2, "leaders"},                       // general label
    {212, kAnyForm, 1, "text strings"},                  // general note
    {213, kAnyForm, 12, "text strings"},                 // new general note
    {214, kAnyForm, 1, "segments"},                      // leader arrow
    {228, kAnyForm, 2, "geometry entities"},             // general symbol: NG
    {228, kAnyForm, 3, "leaders", 2, 3},                 //   NL after the NG pointers
    {302, kAnyForm, 1, "classes"},                       // associativity definition
    {304, 2, 1, "pattern segments"},                     // line font definition, pattern
    {310, kAnyForm, 5, "characters"},                    // text font definition
    {316, kAnyForm, 1, "units"},                         // units data
    {320, kAnyForm, 3, "entities"},                      // network subfigure definition: N
    {320, kAnyForm, 7, "connect points", 3, 4},          //   NC after the N pointers
    {322, kAnyForm, 3, "attributes"},                    // attribute table definition
    {402, 3, 1, "views"},                                // views visible
    {402, 4, 1, "views"},                                // views visible with attributes
    {402, 5, 1, "labels"},                               // label display
    {402, 12, 1, "references"},                          // external reference file index
    {402, 18, 2, "flow entities"},                       // flow: NFE, NCP, NJ, NFN, NTX, NCF
    {402, 18, 3, "connect points"},
    {402, 18, 4, "joins"},
    {402, 18, 5, "flow names"},
    {402, 18, 6, "text displays"},
    {402, 18, 7, "continuation flows"},
    {402, 19, 1, "views"},                               // segmented views visible
    {402, 20, 2, "flow entities"},                       // piping flow: as flow
    {402, 20, 3, "connect points"},
    {402, 20, 4, "joins"},
    {402, 20, 5, "flow names"},
    {402, 20, 6, "text displays"},
    {402, 20, 7, "continuation flows"},
    {402, 21, 2, "geometry entities"},                   // new dimensioned geometry
    {404, 0, 1, "views"},                                // drawing
    {404, 1, 1, "views"},                                // drawing with rotation
    {406, kAnyForm, 1, "property values"},               // every property: NP
    {406, 11, 3, "dependent variables"},                 // tabular data: ND
    {406, 11, 4, "independent variables"},               //   NI
    {406, 24, 2, "layers"},                              // level to PWB layer map
    {406, 25, 3, "levels"},                              // PWB artwork stackup
    {406, 27, 3, "values"},                              // generic data
    {406, 30, 13, "supplementary notes"},                // dimension display data
    {412, kAnyForm, 11, "listed positions"},             // rectangular array subfigure
    {414, kAnyForm, 9, "listed positions"},              // circular array subfigure
    {418, kAnyForm, 1, "constraint cases"},              // nodal constraint
    {420, kAnyForm, 11, "connect points"},               // network subfigure
    {422, kAnyForm, 1, "rows"},                          // attribute table
    {502, 1, 1, "vertices"},                             // vertex list
    {504, 1, 1, "edges"},                                // edge list
    {508, kAnyForm, 1, "edges"},                         // loop
    {510, 1, 2, "loops"},                                // face
    {514, kAnyForm, 1, "faces"},                         // shell
};

// Counts inside repeated items: `count_at` items from `first`, each of `fixed` parameters, the `inner`-th of which
// counts the `per_inner` parameters that follow it.
struct NestedCounts {
  int type;
  int form;
  std::size_t count_at, first, fixed, inner, per_inner;
  const char* what;
};
constexpr NestedCounts kNested[] = {
    {302, kAnyForm, 1, 2, 3, 3, 1, "items"},     // associativity definition: each class BP, OR, NI, then NI items
    {310, kAnyForm, 5, 6, 4, 4, 3, "motions"},   // text font: each character ASCII, NX, NY, NM, then NM × (PF, X, Y)
    {322, 1, 3, 4, 3, 3, 1, "values"},           // attribute table definition: AT, AVDT, AVC, then AVC values
    {322, 2, 3, 4, 3, 3, 2, "values"},           //   and a text template with each value
    {508, kAnyForm, 1, 2, 5, 5, 2, "curves"},    // loop: each edge TYPE, EDGE, NDX, OF, K, then K × (ISO, CURVE)
};

bool applies(int type, int form, const Entity& e) {
  return type == e.type && (form == kAnyForm || form == e.form);
}

std::optional<std::string> too_few(const Entity& e) {
  Check c(e);
  const auto n = static_cast<long double>(e.count());
  for (const CountAt& r : kCounts) {
    if (!applies(r.type, r.form, e)) continue;
    std::size_t at = r.at;
    if (r.list_count_at != 0) {
      // OpenCASCADE's cursor passes the list only when it was read, i.e. when it lies within the parameters.
      const std::optional<long double> listed = c.at(r.list_count_at);
      if (listed && *listed > 0 && static_cast<long double>(r.list_from) + *listed - 1 <= n) {
        at += static_cast<std::size_t>(*listed);
      }
    }
    if (const auto v = c.at(at)) c.need(r.what, *v);
  }
  for (const NestedCounts& r : kNested) {
    if (!applies(r.type, r.form, e)) continue;
    const std::optional<long double> items = c.at(r.count_at);
    if (!items || *items <= 0 || *items > n) continue;  // a count beyond the data is refused above
    std::size_t pos = r.first;
    for (long long i = 0; i < static_cast<long long>(*items) && static_cast<long double>(pos) <= n; ++i) {
      const std::optional<long double> inner = c.at(pos + r.inner - 1);
      if (inner) c.need(r.what, *inner);
      pos += r.fixed + (inner && *inner > 0 ? static_cast<std::size_t>(*inner) * r.per_inner : 0);
    }
  }
  // Products of two counts, each within the data on its own.
  const auto product = [&](std::size_t a, std::size_t b, long double plus, const char* what) {
    const auto x = c.at(a), y = c.at(b);
    if (x && y) c.need(what, (*x + plus) * (*y + plus));
  };
  switch (e.type) {
    case 126:  // B-spline curve: poles 0..K made as soon as K reads (IGESGeom_ToolBSplineCurve)
      if (const auto k = c.at(1); k && *k >= 0) c.need("poles", *k + 1);
      break;
    case 128:  // B-spline surface: weights and poles (0..K1) × (0..K2) as soon as K1 and K2 read
      product(1, 2, 1, "poles");
      break;
    case 114:  // parametric spline surface: M × N patches
      product(3, 4, 0, "patches");
      break;
    case 146:  // nodal results: NN × NV values
      product(5, 4, 0, "nodal values");
      break;
    case 138:  // nodal displacement and rotation: NN nodes × NC cases, each case 6 values (NN after NC notes)
      if (const auto cases = c.at(1); cases && *cases >= 0 && *cases <= n) {
        if (const auto nodes = c.at(2 + static_cast<std::size_t>(*cases))) c.need("node cases", *cases * *nodes);
      }
      break;
    case 406:  // tabular data: NV values for each of the NI independent variables
      if (e.form != 11) break;
      if (const auto ni = c.at(4); ni && *ni > 0 && *ni <= n) {
        const auto k = static_cast<std::size_t>(*ni);
        for (std::size_t i = 1; i <= k; ++i) {
          if (const auto v = c.at(4 + k + i)) c.need("values of an independent variable", *v);
        }
      }
      break;
    default:
      break;
  }
  return std::move(c).reason();
}

// igesread's parameter types (igesread.h) that ReadInteger takes: unsigned and signed integers, and the empty one.
std::optional<int> as_integer(int kind, const char* text) {
  if (kind == ArgInt || kind == ArgSign) return std::atoi(text);
  if (kind == ArgVide) return 0;
  return std::nullopt;
}

// Frees the lexer's pages however the walk ends.
struct LexerPages {
  ~LexerPages() { iges_finfile(0); }
};

}  // namespace

std::optional<std::string> iges_count_beyond_data(const std::filesystem::path& path) {
  // igesread reads standard input for a one-character name. Nothing on the heap in this frame while it runs: a
  // crash inside it (tests/data/fuzz/cad_iges-occt-segv-iges_newparam.igs) jumps back to the caller's
  // OCC_CATCH_SIGNALS past this frame's destructors (occt::CrashGuard).
  char short_name[8] = "./";
  const char* name = path.c_str();
  if (std::char_traits<char>::length(name) < 2) {
    std::char_traits<char>::copy(short_name + 2, name, std::char_traits<char>::length(name) + 1);
    name = short_name;
  }
  int sections[6] = {};
  const int read = igesread(const_cast<char*>(name), sections, 0);
  const LexerPages pages;  // igesread made them before it could fail
  if (read != 0) return std::nullopt;
  int parts = 0, parameters = 0;
  iges_stats(&parts, &parameters);
  // Thread-local rather than on this frame: should the lexer's lists crash the walk, the jump back to the caller
  // skips this frame's destructors, and a vector of this frame would be lost (a leak to LeakSanitizer's fuzzing).
  thread_local Entity e;
  struct Release {
    Entity& e;
    ~Release() { e.integers = {}; }  // the largest entity's values are not kept between files
  } release{e};
  for (int k = 0; k < parts; ++k) {
    int* directory = nullptr;
    char *res1 = nullptr, *res2 = nullptr, *label = nullptr, *subscript = nullptr;
    int n = 0;
    const int line = iges_lirpart(&directory, &res1, &res2, &label, &subscript, &n);
    if (line == 0) break;
    // The directory entry's fields start the lexer's struct dirpart, whose first member `directory` points to.
    const auto* entry = reinterpret_cast<const dirpart*>(directory);
    e.type = entry->typ;
    e.form = entry->form;
    e.directory_line = line;
    e.integers.clear();
    int kind = 0;
    char* text = nullptr;
    // The first parameter repeats the entity type; OpenCASCADE's reader numbers the rest from 1.
    for (bool first = true; iges_lirparam(&kind, &text) != 0; first = false) {
      if (!first) e.integers.push_back(as_integer(kind, text));
    }
    if (std::optional<std::string> r = too_few(e)) return r;
    iges_nextpart();
  }
  return std::nullopt;
}

}  // namespace probecomp::cad
