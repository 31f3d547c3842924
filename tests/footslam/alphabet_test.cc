#include "engine/footslam/alphabet.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <utility>

namespace grove::footslam {
namespace {

Alphabet Make(int t) {
  StatusOr<Alphabet> a = Alphabet::Create(t);
  EXPECT_TRUE(a.ok()) << a.status().ToString();
  return *std::move(a);
}

int Pow(int b, int e) {
  int p = 1;
  while (e-- > 0) p *= b;
  return p;
}

TEST(AlphabetTest, SymbolCountIsMaxCountPlusOneToTheSixth) {
  for (int t = 1; t <= 5; ++t) {
    const Alphabet a = Make(t);
    EXPECT_EQ(a.max_count(), t);
    EXPECT_EQ(a.symbol_count(), Pow(t + 1, 6));
  }
  EXPECT_LT(Make(5).symbol_count(), Alphabet::kOverflow);
}

TEST(AlphabetTest, EverySymbolRoundTripsThroughDecodeAndEncode) {
  for (int t = 1; t <= 5; ++t) {
    SCOPED_TRACE(testing::Message() << "T = " << t);
    const Alphabet a = Make(t);
    for (int s = 0; s < a.symbol_count(); ++s) {
      uint32_t c[6];
      a.Decode(static_cast<uint16_t>(s), c);
      int value = 0;  // the mixed-radix reading, counter 0 least significant
      for (int e = 0; e < 6; ++e) {
        ASSERT_LE(c[e], static_cast<uint32_t>(t));
        value += static_cast<int>(c[e]) * Pow(t + 1, e);
      }
      ASSERT_EQ(value, s);
      ASSERT_EQ(a.Encode(c), s);
    }
  }
}

TEST(AlphabetTest, FirstAndLastSymbolsAreAllZeroAndAllMax) {
  for (int t = 1; t <= 5; ++t) {
    const Alphabet a = Make(t);
    const uint32_t zeros[6] = {0, 0, 0, 0, 0, 0};
    const uint32_t tt = static_cast<uint32_t>(t);
    const uint32_t maxes[6] = {tt, tt, tt, tt, tt, tt};
    EXPECT_EQ(a.Encode(zeros), 0);
    EXPECT_EQ(a.Encode(maxes), a.symbol_count() - 1);
    EXPECT_EQ(a.Total(0), 0u);
    EXPECT_EQ(a.Total(static_cast<uint16_t>(a.symbol_count() - 1)), 6u * tt);
  }
}

TEST(AlphabetTest, NextOfSymbolZeroIsOneCountOnThatEdge) {
  // The paper's Fig. 6.
  const Alphabet a = Make(3);
  for (int e = 0; e < 6; ++e) {
    uint32_t c[6];
    a.Decode(a.Next(0, e), c);
    for (int k = 0; k < 6; ++k) EXPECT_EQ(c[k], k == e ? 1u : 0u) << "edge " << e;
  }
}

TEST(AlphabetTest, NextAgreesWithDecodeIncrementEncodeAndOverflowsExactlyAtMax) {
  for (int t = 1; t <= 5; ++t) {
    SCOPED_TRACE(testing::Message() << "T = " << t);
    const Alphabet a = Make(t);
    for (int s = 0; s < a.symbol_count(); ++s) {
      const uint16_t sym = static_cast<uint16_t>(s);
      uint32_t c[6];
      a.Decode(sym, c);
      uint32_t total = 0;
      for (int e = 0; e < 6; ++e) {
        ASSERT_EQ(a.Count(sym, e), c[e]);
        total += c[e];
        if (c[e] == static_cast<uint32_t>(t)) {
          ASSERT_EQ(a.Next(sym, e), Alphabet::kOverflow) << "symbol " << s << " edge " << e;
        } else {
          uint32_t up[6];
          for (int k = 0; k < 6; ++k) up[k] = c[k] + (k == e ? 1 : 0);
          ASSERT_EQ(a.Next(sym, e), a.Encode(up)) << "symbol " << s << " edge " << e;
        }
      }
      ASSERT_EQ(a.Total(sym), total);
    }
  }
}

TEST(AlphabetTest, RepeatedCrossingsOfOneEdgeOverflowOnTheCrossingAfterT) {
  for (int t = 1; t <= 5; ++t) {
    const Alphabet a = Make(t);
    for (int e = 0; e < 6; ++e) {
      uint16_t s = 0;
      for (int i = 0; i < t; ++i) {
        s = a.Next(s, e);
        ASSERT_NE(s, Alphabet::kOverflow) << "T = " << t << " edge " << e << " crossing " << i;
      }
      EXPECT_EQ(a.Count(s, e), static_cast<uint32_t>(t));
      EXPECT_EQ(a.Total(s), static_cast<uint32_t>(t));
      EXPECT_EQ(a.Next(s, e), Alphabet::kOverflow);
    }
  }
}

TEST(AlphabetTest, CreateRejectsValuesOutsideOneToFive) {
  for (int bad : {0, -1, 6, 100}) {
    const StatusOr<Alphabet> a = Alphabet::Create(bad);
    ASSERT_FALSE(a.ok()) << bad;
    EXPECT_EQ(a.status().code(), StatusCode::kInvalidArgument);
    EXPECT_EQ(a.status().message(), "alphabet = " + std::to_string(bad) +
                                        ": must be in 1..5 (0 switches the alphabet off)");
  }
}

}  // namespace
}  // namespace grove::footslam
