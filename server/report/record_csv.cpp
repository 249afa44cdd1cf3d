#include "server/report/record_csv.h"

#include <algorithm>
#include <charconv>

#include <fmt/format.h>

#include "maps/scenario/scenario.h"

namespace sage::server::detail {

std::vector<std::string> SplitCsvLine(std::string_view line) {
  std::vector<std::string> fields;
  std::size_t i = 0;
  while (i <= line.size()) {
    std::string field;
    if (i < line.size() && line[i] == '"') {
      ++i;
      while (i < line.size()) {
        if (line[i] == '"' && i + 1 < line.size() && line[i + 1] == '"') field += '"', i += 2;
        else if (line[i] == '"') { ++i; break; }
        else field += line[i++];
      }
      while (i < line.size() && line[i] != ',') ++i;
    } else {
      const std::size_t comma = std::min(line.find(',', i), line.size());
      field = std::string(line.substr(i, comma - i));
      i = comma;
    }
    fields.push_back(std::move(field));
    if (i >= line.size()) break;
    ++i;  // the comma
  }
  return fields;
}

double NumberField(const std::string& text, const std::string& path, long line) {
  double value = 0.0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || ptr != text.data() + text.size()) {
    throw maps::ScenarioError(fmt::format("{}:{}: '{}' is not a number", path, line, text));
  }
  return value;
}

}  // namespace sage::server::detail
