#include "runtime/scene/scene_file_yaml.h"

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <sstream>
#include <unordered_map>

#include "runtime/scene/scene_file.h"

namespace fmpc::sim {

std::string join_names(const std::vector<std::string>& names) {
  std::string text;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i > 0) text += i + 1 == names.size() ? " or " : ", ";
    text += names[i];
  }
  return text;
}

SourceRange mark_range(const std::string& path, const YAML::Mark& mark) {
  SourceRange r;
  r.file = path;
  if (mark.line >= 0) {
    r.line = mark.line + 1;
    r.column = mark.column + 1;
    r.end_line = r.line;
    r.end_column = r.column + 1;
  }
  return r;
}

namespace {

// The event handler of scan_scene_yaml: one frame per open map or list, with the keys seen so far.
class SceneYamlScan : public YAML::EventHandler {
 public:
  struct TooDeep {
    YAML::Mark mark;
  };

  SceneYamlScan(const std::string& path, DiagnosticList& diagnostics) : path_(path), diagnostics_(diagnostics) {}

  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& mark, YAML::anchor_t) override { node_done(mark, nullptr); }
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t) override { node_done(mark, nullptr); }
  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t, const std::string& value) override {
    node_done(mark, &value);
  }
  void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    open(mark, false);
  }
  void OnSequenceEnd() override { close(); }
  void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    open(mark, true);
  }
  void OnMapEnd() override { close(); }

 private:
  struct Frame {
    bool map = false;
    bool expecting_key = true;
    std::size_t items = 0;
    std::string field;  // "loads.probe", "fixed.box[1]"
    std::string pending_key;
    std::unordered_map<std::string, YAML::Mark> keys;
  };

  std::string child_field() const {
    if (frames_.empty()) return "";
    const Frame& parent = frames_.back();
    if (parent.map) return parent.field.empty() ? parent.pending_key : parent.field + "." + parent.pending_key;
    return parent.field + "[" + std::to_string(parent.items) + "]";
  }

  void open(const YAML::Mark& mark, bool map) {
    if (frames_.size() >= kMaxSceneNesting) throw TooDeep{mark};
    Frame frame;
    frame.map = map;
    frame.field = child_field();
    frames_.push_back(std::move(frame));
  }

  void close() {
    frames_.pop_back();
    node_done(YAML::Mark(), nullptr);
  }

  // A whole node has been read at the level of frames_.back(): a key or a value of a map, or a list item.
  void node_done(const YAML::Mark& mark, const std::string* scalar) {
    if (frames_.empty()) return;
    Frame& frame = frames_.back();
    if (!frame.map) {
      ++frame.items;
      return;
    }
    if (!frame.expecting_key) {
      frame.expecting_key = true;
      return;
    }
    frame.expecting_key = false;
    frame.pending_key = scalar ? *scalar : std::string();
    if (!scalar) return;  // a complex key: the scene parser reports it as unknown
    const auto [first, inserted] = frame.keys.emplace(*scalar, mark);
    if (inserted) return;
    const std::string field = frame.field.empty() ? *scalar : frame.field + "." + *scalar;
    diagnostics_.error(mark_range(path_, mark), field + ": duplicate key; YAML keeps only one of the two, so remove one",
                       {"first given here: " + std::to_string(first->second.line + 1) + ":" +
                        std::to_string(first->second.column + 1)});
  }

  std::string path_;
  DiagnosticList& diagnostics_;
  std::vector<Frame> frames_;
};

}  // namespace

void scan_scene_yaml(const std::string& path, const std::string& text, DiagnosticList& diagnostics) {
  try {
    std::istringstream stream(text);
    YAML::Parser events(stream);
    SceneYamlScan scan(path, diagnostics);
    if (events.HandleNextDocument(scan)) {
      // A second document would be ignored by YAML::Load.
      SceneYamlScan rest(path, diagnostics);
      if (events.HandleNextDocument(rest))
        diagnostics.error(SourceRange{path, 0, 0, 0, 0},
                          "the file holds more than one YAML document ('---'); a scene file is one document");
    }
  } catch (const SceneYamlScan::TooDeep& too_deep) {
    diagnostics.error(mark_range(path, too_deep.mark),
                      "the YAML nests deeper than " + std::to_string(kMaxSceneNesting) +
                          " levels; a scene needs about 6: check the indentation and brackets");
  }
}

}  // namespace fmpc::sim
