#include "tools/report/report_tables.h"

#include <gtest/gtest.h>

namespace grove::tools {
namespace {

TEST(CsvTableTest, QuotesOnlyFieldsThatNeedIt) {
  EXPECT_EQ(
      CsvTable({"name", "particles", "ms"}, {{"a", "1000", "1.5"}, {"b,c", "say \"hi\"", ""}}),
      "name,particles,ms\n"
      "a,1000,1.5\n"
      "\"b,c\",\"say \"\"hi\"\"\",\n");
  EXPECT_EQ(CsvTable({"x"}, {{"two\nlines"}, {"cr\r"}}), "x\n\"two\nlines\"\n\"cr\r\"\n");
  EXPECT_EQ(CsvTable({}, {{"1", "2"}}), "1,2\n");
  EXPECT_EQ(CsvTable({"only"}, {}), "only\n");
  EXPECT_EQ(CsvTable({}, {}), "");
}

TEST(MarkdownTableTest, PipesAndHeaderSeparator) {
  EXPECT_EQ(MarkdownTable({"name", "ms"}, {{"a", "1.5"}, {"b", "20"}}),
            "| name | ms |\n"
            "| --- | --- |\n"
            "| a | 1.5 |\n"
            "| b | 20 |\n");
  // Short rows are padded, pipes escaped, line breaks turned into <br>.
  EXPECT_EQ(MarkdownTable({"k", "v"}, {{"a|b"}, {"x", "1\n2"}, {"y", "3\r\n4"}}),
            "| k | v |\n"
            "| --- | --- |\n"
            "| a\\|b |  |\n"
            "| x | 1<br>2 |\n"
            "| y | 3<br>4 |\n");
  // A row longer than the header widens the table.
  EXPECT_EQ(MarkdownTable({"a"}, {{"1", "2"}}),
            "| a |  |\n"
            "| --- | --- |\n"
            "| 1 | 2 |\n");
  EXPECT_EQ(MarkdownTable({}, {}), "");
}

}  // namespace
}  // namespace grove::tools
