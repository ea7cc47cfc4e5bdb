// EnumNames: parsing, printing and the messages derived from one table.
#include "core/enum_names.h"

#include <gtest/gtest.h>

namespace {

using namespace reliefsim;

enum class Fruit { Apple, Pear };
constexpr auto kFruitNames = MakeEnumNames<Fruit>({
    {"apple", Fruit::Apple},
    {"pear", Fruit::Pear},
});
constexpr auto kLetterNames = MakeEnumNames<Fruit>(
    {
        {"A", Fruit::Apple},
        {"P", Fruit::Pear},
    },
    /*ignoreCase=*/true);

// The table is usable at compile time.
static_assert(kFruitNames.Parse("pear") == Fruit::Pear);
static_assert(kFruitNames.Name(Fruit::Apple) == "apple");

}  // namespace

TEST(EnumNames, ParsesOnlyTheNamesInTheirCase) {
    EXPECT_EQ(kFruitNames.Parse("apple"), Fruit::Apple);
    for (const char* bad : {"Apple", "APPLE", "apples", "", "0", "1", " apple"})
        EXPECT_FALSE(kFruitNames.Parse(bad).has_value()) << bad;
}

TEST(EnumNames, IgnoreCaseMatchesEitherCaseAndPrintsTheTableSpelling) {
    EXPECT_EQ(kLetterNames.Parse("p"), Fruit::Pear);
    EXPECT_EQ(kLetterNames.Parse("P"), Fruit::Pear);
    EXPECT_FALSE(kLetterNames.Parse("pp").has_value());
    EXPECT_EQ(kLetterNames.Name(Fruit::Pear), "P");
}

TEST(EnumNames, UnknownValueIsNamedWithTheValidNames) {
    EXPECT_EQ(kFruitNames.Name(Fruit(7)), "?");
    EXPECT_EQ(kFruitNames.Join("|"), "apple|pear");
    EXPECT_EQ(kFruitNames.Unknown("plum"),
              "\"plum\" is unknown; must be one of: \"apple\", \"pear\"");
}
