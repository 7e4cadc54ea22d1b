// The bounded excerpt every message quotes user input through (issue 28): a key of 200,000
// characters or a 1 MB string is cut to 60 characters with its length, whole UTF-8 characters,
// control characters escaped.
#include "core/excerpt.hpp"

#include <gtest/gtest.h>

#include <string>

#include "core/error.hpp"

namespace glaswave {
namespace {

TEST(Excerpt, ShortTextIsWhole) {
  EXPECT_EQ(excerpt("pai"), "pai");
  EXPECT_EQ(quoted_excerpt("pai"), "\"pai\"");
  EXPECT_EQ(quoted_excerpt(std::string(60, 'a')), "\"" + std::string(60, 'a') + "\"");
}

TEST(Excerpt, LongTextIsCutWithItsLength) {
  const std::string key(200000, 'k');
  EXPECT_EQ(quoted_excerpt(key), "\"" + std::string(60, 'k') + "...\" (200000 characters)");
  EXPECT_EQ(excerpt(std::string(61, 'x')), std::string(60, 'x') + "... (61 characters)");
}

TEST(Excerpt, CountsAndCutsWholeUtf8Characters) {
  std::string text;
  for (int i = 0; i < 70; ++i) text += "\xC3\xA9";  // é, two bytes
  const std::string cut = excerpt(text);
  EXPECT_EQ(cut.substr(0, 120), text.substr(0, 120));
  EXPECT_EQ(cut.substr(120), "... (70 characters)");
}

TEST(Excerpt, EscapesControlCharacters) {
  EXPECT_EQ(quoted_excerpt("p\x1b[31mai\n"), "\"p\\x1b[31mai\\x0a\"");
}

TEST(Excerpt, AnErrorPlaceLongerThanAnyPathIsAnExcerpt) {
  const Error error(ErrorKind::input, std::string(1 << 20, 'p'), "cannot open the DEM");
  EXPECT_EQ(error.place(), std::string(60, 'p') + "... (1048576 characters)");
  EXPECT_LT(std::string(error.what()).size(), 200u);
  const std::string path = "/" + std::string(300, 'd') + "/dem.tif";  // long, but a path
  EXPECT_EQ(Error(ErrorKind::input, path, "x").place(), path);
}

}  // namespace
}  // namespace glaswave
