// core/parse.h: strict number parsing, and FloatText's way back.
#include "core/parse.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace reliefsim {
namespace {

float FromBits(uint32_t b) {
    float f;
    std::memcpy(&f, &b, sizeof f);
    return f;
}

TEST(FloatText, ReadsBackAsTheSameFloat) {
    using L = std::numeric_limits<float>;
    for (float v : {0.0f, -0.0f, 1.0f, 30.0f, 0.1f, -0.1f, 1.0f / 3.0f, 89.99f, 1e-30f,
                    L::max(), -L::max(), L::min(), L::denorm_min(), L::epsilon(),
                    std::nextafter(1.0f, 2.0f), std::nextafter(0.1f, 0.0f)}) {
        const auto back = ParseFiniteFloat(FloatText(v));
        ASSERT_TRUE(back) << FloatText(v);
        EXPECT_EQ(*back, v) << FloatText(v);
        EXPECT_EQ(std::signbit(*back), std::signbit(v)) << FloatText(v);
    }
    // Every 2^20th bit pattern of the finite floats.
    for (uint64_t b = 0; b < (uint64_t(1) << 32); b += uint64_t(1) << 20) {
        const float v = FromBits(uint32_t(b));
        if (!std::isfinite(v)) continue;
        const auto back = ParseFiniteFloat(FloatText(v));
        ASSERT_TRUE(back) << FloatText(v);
        EXPECT_EQ(*back, v) << FloatText(v);
    }
    EXPECT_EQ(FloatText(30.0f), "30");
    EXPECT_EQ(FloatText(0.5f), "0.5");
    EXPECT_EQ(FloatText(0.1f), "0.100000001");
}

TEST(ParseFiniteFloat, TheWholeTextAndFiniteOnly) {
    EXPECT_EQ(ParseFiniteFloat("2.5"), 2.5f);
    EXPECT_EQ(ParseFiniteFloat("-1e3"), -1000.0f);
    for (const char* bad :
         {"", " 1", "1 ", "1x", "0x10", "+1", "nan", "inf", "1e39", "--1"})
        EXPECT_FALSE(ParseFiniteFloat(bad)) << bad;
    // The overflow threshold: 2^128 - 2^103 (halfway from the largest float to 2^128)
    // rounds to infinity, anything below it to the largest float.
    EXPECT_EQ(ParseFiniteFloat("3.40282347e+38"), std::numeric_limits<float>::max());
    EXPECT_EQ(ParseFiniteFloat("-3.4028235677973e38"),
              -std::numeric_limits<float>::max());
    EXPECT_FALSE(ParseFiniteFloat("3.4028235677973366e38"));  // 2^128 - 2^103
    EXPECT_FALSE(ParseFiniteFloat("3.5e38"));
}

TEST(LooksLikeDecimal, FromCharsWholeTextOnly) {
    for (const char* good : {"1", "-1", "0.5", ".5", "5.", "1e3", "-2.5E-3", "010",
                             "1e999", "3.40282347e+38", "inf", "nan"})
        EXPECT_TRUE(LooksLikeDecimal(good)) << good;
    for (const char* bad :
         {"", "+1", " 1", "1 ", "0x10", "0x1p3", "1_0", "1,5", "--1", "-", "e3", "1e"})
        EXPECT_FALSE(LooksLikeDecimal(bad)) << bad;
}

TEST(ParseIntInRange, DecimalOnlyAndNamedOnError) {
    EXPECT_EQ(ParseIntInRange("010", 0, 100, "--n"), 10);
    EXPECT_EQ(ParseIntInRange("-5", -10, 10, "--n"), -5);
    for (const char* bad : {"0x10", "1e1", "+1", " 1", "", "99999999999999999999"}) {
        try {
            ParseIntInRange(bad, 0, 100, "--n");
            ADD_FAILURE() << bad;
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("--n \""), std::string::npos)
                << e.what();
        }
    }
    EXPECT_THROW(ParseIntInRange("101", 0, 100, "--n"), Error);
}

}  // namespace
}  // namespace reliefsim
