#include "grove/status.h"

#include <gtest/gtest.h>

#include <memory>
#include <string>

namespace grove {
namespace {

TEST(StatusOrTest, HoldsValueOrError) {
  StatusOr<int> value(7);
  ASSERT_TRUE(value.ok());
  EXPECT_EQ(*value, 7);
  StatusOr<int> error(InvalidArgumentError("bad"));
  EXPECT_FALSE(error.ok());
  EXPECT_EQ(error.status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(error.status().message(), "bad");
}

TEST(StatusOrTest, MadeFromOkStatusIsAnInternalErrorNotAnEmptyValue) {
  StatusOr<std::unique_ptr<int>> s(Status::Ok());
  EXPECT_FALSE(s.ok());
  EXPECT_EQ(s.status().code(), StatusCode::kInternal);
}

TEST(QuoteForMessageTest, EscapesEveryByteOutsidePrintableAscii) {
  EXPECT_EQ(QuoteForMessage("abc"), "\"abc\"");
  EXPECT_EQ(QuoteForMessage(std::string("a\nb\0c\x1b[", 7)), "\"a\\x0ab\\x00c\\x1b[\"");
  EXPECT_EQ(QuoteForMessage("say \"hi\"\\"), "\"say \\x22hi\\x22\\x5c\"");
  EXPECT_EQ(QuoteForMessage("\xc3\xa9"), "\"\\xc3\\xa9\"");
}

TEST(QuoteForMessageTest, CutsLongTextWithAnEllipsis) {
  std::string quoted = QuoteForMessage(std::string(10000, 'x'), 10);
  EXPECT_EQ(quoted, "\"xxxxxxxxxx...\"");
  EXPECT_EQ(QuoteForMessage("xxxxxxxxxx", 10), "\"xxxxxxxxxx\"");
}

}  // namespace
}  // namespace grove
