// "Did you mean": edit distances counted by hand, and the suggestions a user's typos should get.
#include "core/names.hpp"

#include <gtest/gtest.h>

namespace glaswave {
namespace {

TEST(EditDistance, CountsInsertionsDeletionsAndSubstitutions) {
  EXPECT_EQ(edit_distance("", ""), 0u);
  EXPECT_EQ(edit_distance("pai", "pai"), 0u);
  EXPECT_EQ(edit_distance("pia", "pai"), 2u);  // two substitutions
  EXPECT_EQ(edit_distance("kitten", "sitting"), 3u);
  EXPECT_EQ(edit_distance("simulaton", "simulation"), 1u);
  EXPECT_EQ(edit_distance("", "abc"), 3u);
}

TEST(DidYouMean, SuggestsCloseNamesAndUnitCompletionsOnly) {
  const std::vector<std::string> keys = {"pai", "cover", "slope_deg", "aspect_deg", "rate_hz"};
  EXPECT_EQ(did_you_mean("pia", keys), "; did you mean \"pai\"?");
  EXPECT_EQ(did_you_mean("rate_Hz", keys), "; did you mean \"rate_hz\"?");
  EXPECT_EQ(did_you_mean("slope", keys), "; did you mean \"slope_deg\"?");  // the unit left out
  EXPECT_EQ(did_you_mean("elevation", keys), "");
  EXPECT_EQ(did_you_mean("x", {}), "");
  EXPECT_EQ(nearest_name("covr", keys), "cover");
}

}  // namespace
}  // namespace glaswave
