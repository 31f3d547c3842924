#include "tools/report/report_tables.h"

#include <algorithm>

namespace grove::tools {

std::string CsvTable(const std::vector<std::string>& header,
                     const std::vector<std::vector<std::string>>& rows) {
  std::string out;
  auto append_record = [&out](const std::vector<std::string>& fields) {
    for (size_t i = 0; i < fields.size(); ++i) {
      if (i > 0) out += ',';
      const std::string& f = fields[i];
      if (f.find_first_of(",\"\r\n") == std::string::npos) {
        out += f;
        continue;
      }
      out += '"';
      for (char c : f) {
        if (c == '"') out += '"';
        out += c;
      }
      out += '"';
    }
    out += '\n';
  };
  if (!header.empty()) append_record(header);
  for (const std::vector<std::string>& row : rows) append_record(row);
  return out;
}

std::string MarkdownTable(const std::vector<std::string>& header,
                          const std::vector<std::vector<std::string>>& rows) {
  size_t columns = header.size();
  for (const std::vector<std::string>& row : rows) columns = std::max(columns, row.size());
  if (columns == 0) return "";
  std::string out;
  auto append_line = [&out, columns](const std::vector<std::string>& cells) {
    out += '|';
    for (size_t i = 0; i < columns; ++i) {
      out += ' ';
      if (i < cells.size()) {
        const std::string& cell = cells[i];
        for (size_t j = 0; j < cell.size(); ++j) {
          char c = cell[j];
          if (c == '|') {
            out += "\\|";
          } else if (c == '\n') {
            out += "<br>";
          } else if (c == '\r') {
            if (j + 1 >= cell.size() || cell[j + 1] != '\n') out += "<br>";  // lone CR
          } else {
            out += c;
          }
        }
      }
      out += " |";
    }
    out += '\n';
  };
  append_line(header);
  out += '|';
  for (size_t i = 0; i < columns; ++i) out += " --- |";
  out += '\n';
  for (const std::vector<std::string>& row : rows) append_line(row);
  return out;
}

}  // namespace grove::tools
