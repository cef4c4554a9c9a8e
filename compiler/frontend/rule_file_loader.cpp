#include "compiler/frontend/rule_file_loader.h"

#include <algorithm>
#include <cctype>

#include "compiler/frontend/fll.h"
#include "compiler/frontend/fmpc_language.h"
#include "compiler/frontend/fuzzylite_vocabulary.h"
#include "compiler/frontend/matlab_fis.h"
#include "compiler/frontend/utf8.h"
#include "compiler/sema/check.h"

namespace fmpc {

namespace {

// The first line that is not blank or a comment, without its leading blanks (std::isspace's, as the FLL and FCL
// readers cut lines: a form feed alone on the first line leaves an FCL file FCL).
std::string first_content_line(const std::string& text) {
  std::size_t pos = starts_with_byte_order_mark(text) ? 3 : 0;
  while (pos < text.size()) {
    const std::size_t end = std::min(text.find('\n', pos), text.size());
    const std::size_t first = text.find_first_not_of(" \t\r\v\f", pos);
    if (first < end) {
      const char c = text[first];
      if (text.compare(first, 2, "(*") == 0) {  // FCL block comment, possibly over several lines
        const std::size_t close = text.find("*)", first + 2);
        if (close == std::string::npos) return {};
        pos = close + 2;
        continue;
      }
      if (c != '%' && c != '#' && text.compare(first, 2, "//") != 0) return text.substr(first, end - first);
    }
    pos = end + 1;
  }
  return {};
}

}  // namespace

Dialect detect_dialect(const std::string& text) {
  const std::string line = first_content_line(text);
  if (line.compare(0, 8, "[System]") == 0) return Dialect::Matlab;
  if (looks_like_fll(line)) return Dialect::Fll;
  if (looks_like_fcl(line)) return Dialect::Fcl;
  return Dialect::Fmpc;
}

const char* dialect_name(Dialect dialect) {
  switch (dialect) {
    case Dialect::Fmpc: return "fmpc";
    case Dialect::Matlab: return "MATLAB .fis";
    case Dialect::Fll: return "fuzzylite FLL";
    case Dialect::Fcl: return "IEC 61131-7 FCL";
  }
  return "?";
}

std::string foreign_format(const std::string& text) {
  const std::string line = first_content_line(text);
  if (line.empty()) return {};
  if (line[0] == '<')
    return "an XML file (JFML or another XML format); fmpc reads its own language, MATLAB .fis, fuzzylite FLL and "
           "IEC 61131-7 FCL";
  if (line[0] == '{')
    return "a JSON file; fmpc reads its own language, MATLAB .fis, fuzzylite FLL and IEC 61131-7 FCL";
  // "key: value" at the start of the first line: YAML, which fmpc reads only as scene files.
  std::size_t k = 0;
  while (k < line.size() && (std::isalnum(static_cast<unsigned char>(line[k])) || line[k] == '_')) ++k;
  if (k > 0 && k < line.size() && line[k] == ':' && (k + 1 == line.size() || line[k + 1] == ' '))
    return "a YAML file (a scene?); scenes are run with `fmpc simulate`, rule files are fmpc, MATLAB .fis, FLL or FCL";
  // A header of comma-separated names and nothing else: CSV data.
  if (line.find(',') != std::string::npos && line.find(' ') == std::string::npos &&
      line.find('(') == std::string::npos)
    return "CSV data (a header of comma-separated names); points to evaluate are given with `fmpc eval FILE --csv "
           "POINTS.csv`";
  return {};
}

RuleFile load_rule_file(const std::string& path, const std::string& original, DiagnosticList& diagnostics) {
  const std::string text = blank_byte_order_mark(original);
  const Dialect dialect = detect_dialect(text);
  if (dialect == Dialect::Fmpc) {
    const std::string foreign = foreign_format(text);
    if (!foreign.empty()) {
      diagnostics.error(SourceRange{path, 0, 0, 0, 0}, "this is not a rule file: it looks like " + foreign);
      return RuleFile{path, {}};
    }
  }
  // The MATLAB reader and the fmpc parser check UTF-8 themselves; FLL and FCL names reach every output (Python's
  // str among them), so their text is checked here.
  if ((dialect == Dialect::Fll || dialect == Dialect::Fcl) && report_invalid_utf8(path, text, diagnostics))
    return RuleFile{path, {}};
  RuleFile file;
  switch (dialect) {
    case Dialect::Matlab: file = read_matlab_fis(path, text, diagnostics); break;
    case Dialect::Fll: file = read_fll(path, text, diagnostics); break;
    case Dialect::Fcl: file = read_fcl(path, text, diagnostics); break;
    case Dialect::Fmpc: file = read_fmpc(path, text, diagnostics); break;
  }
  // MATLAB rules name terms by number, so two terms of one variable may share a name there (juggler.fis does);
  // in the fmpc language rules name terms by name, and a duplicate would be ambiguous.
  CheckOptions options;
  options.terms_named_by_index = dialect == Dialect::Matlab;
  for (const FuzzySystem& system : file.systems) check_system(system, options, diagnostics);
  // An empty file, or one of comments only, would otherwise check clean and evaluate nothing.
  if (file.systems.empty() && !diagnostics.has_errors())
    diagnostics.error(SourceRange{path, 0, 0, 0, 0},
                      "the file defines no system (it is empty or holds only comments); a rule file starts with "
                      "'system NAME' (docs/language.md), '[System]' (MATLAB), 'Engine:' (FLL) or 'FUNCTION_BLOCK' "
                      "(FCL)");
  diagnostics.sort_by_position();
  return file;
}

const FuzzySystem* select_system(const RuleFile& rules, const std::string& path, const std::string& name,
                                 DiagnosticList& diagnostics) {
  const auto& systems = rules.systems;
  if (name.empty()) {
    if (systems.size() == 1) return &systems.front();
    if (systems.empty()) {
      diagnostics.error(SourceRange{path, 0, 0, 0, 0}, "the file defines no system");
      return nullptr;
    }
    std::string names;
    for (const FuzzySystem& s : systems) names += (names.empty() ? "" : ", ") + s.name;
    diagnostics.error(SourceRange{path, 0, 0, 0, 0}, "the file defines " + std::to_string(systems.size()) +
                                                         " systems (" + names + "); choose one with --system NAME");
    return nullptr;
  }
  std::vector<std::string> names;
  for (const FuzzySystem& s : systems) {
    if (s.name == name) return &s;
    names.push_back(s.name);
  }
  std::vector<std::string> notes;
  if (auto suggestion = closest_name(name, names)) notes.push_back("did you mean '" + *suggestion + "'?");
  diagnostics.error(SourceRange{path, 0, 0, 0, 0}, "no system named '" + name + "' in the file", notes);
  return nullptr;
}

}  // namespace fmpc
