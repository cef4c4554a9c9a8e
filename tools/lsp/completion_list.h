#pragma once
// A CompletionList (LSP 3.17 textDocument/completion) being gathered: each label once, in the order added. Shared by
// the completion of fmpc-language text (lsp_completion.cpp) and of MATLAB .fis text (lsp_matlab.cpp).
#include <initializer_list>
#include <string>

#include <nlohmann/json.hpp>

namespace fmpc::lsp {

// CompletionItemKind (LSP 3.17).
constexpr int kItemFunction = 3;
constexpr int kItemVariable = 6;
constexpr int kItemProperty = 10;
constexpr int kItemUnit = 11;
constexpr int kItemValue = 12;
constexpr int kItemKeyword = 14;
constexpr int kItemEnumMember = 20;

class Completions {
 public:
  // `insert`: the text to insert instead of the label; a snippet (InsertTextFormat.Snippet) when `snippet`.
  void add(const std::string& label, int kind, const std::string& detail = "", const std::string& insert = "",
           bool snippet = true) {
    for (const nlohmann::json& item : items_)
      if (item["label"] == label) return;
    nlohmann::json item{{"label", label}, {"kind", kind}};
    if (!detail.empty()) item["detail"] = detail;
    if (!insert.empty()) {
      item["insertText"] = insert;
      item["insertTextFormat"] = snippet ? 2 : 1;
    }
    items_.push_back(std::move(item));
  }
  void keywords(std::initializer_list<const char*> words) {
    for (const char* word : words) add(word, kItemKeyword);
  }
  void values(std::initializer_list<const char*> words, const std::string& detail) {
    for (const char* word : words) add(word, kItemValue, detail);
  }
  nlohmann::json list() const { return nlohmann::json{{"isIncomplete", false}, {"items", items_}}; }

 private:
  nlohmann::json items_ = nlohmann::json::array();
};

}  // namespace fmpc::lsp
