#pragma once
// A small JSON writer (RFC 8259) for the run summary: objects, arrays, strings, numbers, booleans. Numbers use
// format_number; NaN and infinities, which JSON cannot hold, are written as null.
#include <string>
#include <vector>

namespace fmpc::sim {

class JsonWriter {
 public:
  JsonWriter& begin_object(const std::string& key = "");
  JsonWriter& end_object();
  JsonWriter& begin_array(const std::string& key = "");
  JsonWriter& end_array();
  JsonWriter& value(const std::string& key, double number);
  JsonWriter& value(const std::string& key, long long number);
  JsonWriter& value(const std::string& key, std::size_t number);
  JsonWriter& value(const std::string& key, bool flag);
  JsonWriter& value(const std::string& key, const std::string& text);
  JsonWriter& value(const std::string& key, const char* text);
  JsonWriter& element(double number);  // inside an array
  // The document, with a final newline.
  std::string str() const;

 private:
  void prefix(const std::string& key);
  std::string out_;
  std::vector<bool> first_;  // per open container: no member written yet
};

std::string json_quote(const std::string& text);

}  // namespace fmpc::sim
