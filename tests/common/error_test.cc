// InputError's message: what the user sees of a bad value.

#include "common/error.h"

#include <gtest/gtest.h>

#include <string>

namespace hgrasp {
namespace {

TEST(InputErrorTest, NamesFileFieldValueAndExpected) {
  const InputError e("a.yaml:3", "objects[0].mass", "heavy", "a mass in kg");
  EXPECT_STREQ(e.what(), "a.yaml:3: objects[0].mass: got 'heavy'; expected a mass in kg");
  EXPECT_EQ(e.value(), "heavy");
}

// Binary garbage was cut at its first NUL byte (what() is a C string) and control bytes went to
// the terminal raw; now every byte that is not printable shows as \xNN.
TEST(InputErrorTest, BinaryValuesAreShownEscapedAndWhole) {
  const std::string garbage("ab\0c\x1b[2J\x7f", 9);
  const InputError e("f.yaml", std::string("ke\0y", 4), garbage, "text");
  const std::string what = e.what();
  EXPECT_EQ(what, "f.yaml: ke\\x00y: got 'ab\\x00c\\x1b[2J\\x7f'; expected text");
  EXPECT_EQ(e.value(), garbage);  // the value itself is kept as it was
  // UTF-8 passes through.
  EXPECT_NE(std::string(InputError("", "", "gr\xc3\xbcn", "").what()).find("gr\xc3\xbcn"),
            std::string::npos);
}

TEST(InputErrorTest, LongValuesAreCut) {
  const InputError e("f.yaml", "name", std::string(100000, '['), "a name");
  EXPECT_LT(std::string(e.what()).size(), 300u);
  EXPECT_NE(std::string(e.what()).find("[[[...'"), std::string::npos) << e.what();
}

}  // namespace
}  // namespace hgrasp
