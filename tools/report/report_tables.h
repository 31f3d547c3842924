// Tables of benchmark numbers for reports: CSV for tools, Markdown for people.
#ifndef GROVE_TOOLS_REPORT_REPORT_TABLES_H_
#define GROVE_TOOLS_REPORT_REPORT_TABLES_H_

#include <string>
#include <vector>

namespace grove::tools {

// RFC 4180 CSV: a field holding a comma, a double quote, CR or LF is quoted with inner quotes
// doubled; every record, the header included, ends with "\n". An empty header writes no header
// line. Rows are written as given, whatever their length.
std::string CsvTable(const std::vector<std::string>& header,
                     const std::vector<std::vector<std::string>>& rows);

// A GitHub-flavoured Markdown table: "| a | b |", then "| --- | --- |", then one line per row.
// Every line gets as many cells as the longest of header and rows (missing cells are empty);
// "|" in a cell is escaped as "\|" and a line break becomes "<br>". Empty input gives "".
std::string MarkdownTable(const std::vector<std::string>& header,
                          const std::vector<std::vector<std::string>>& rows);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_REPORT_REPORT_TABLES_H_
