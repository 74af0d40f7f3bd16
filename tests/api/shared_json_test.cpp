// SharedJson: the status snapshot's kind details, shared by copies, private once changed.
#include <gtest/gtest.h>

#include "api/backend.hpp"

namespace liftd::api {
namespace {

TEST(SharedJson, DefaultIsAnEmptyObject) {
  const SharedJson a;
  EXPECT_TRUE(a->is_object());
  EXPECT_TRUE(a->empty());
  EXPECT_EQ(a, SharedJson{});
}

TEST(SharedJson, CopiesShareOneValue) {
  const SharedJson a(nlohmann::json{{"mode", "DCP4"}});
  const SharedJson b = a;  // NOLINT(performance-unnecessary-copy-initialization)
  EXPECT_EQ(&*a, &*b);
  EXPECT_EQ(a, b);
}

TEST(SharedJson, EqualValuesBuiltApartCompareEqual) {
  const SharedJson a(nlohmann::json{{"mode", "DCP4"}, {"ready", true}});
  const SharedJson b(nlohmann::json{{"mode", "DCP4"}, {"ready", true}});
  EXPECT_NE(&*a, &*b);
  EXPECT_EQ(a, b);
  EXPECT_FALSE(a == SharedJson(nlohmann::json{{"mode", "DCP3"}, {"ready", true}}));
}

TEST(SharedJson, EditChangesOnlyThisCopy) {
  SharedJson a(nlohmann::json{{"speed", 1}});
  const SharedJson b = a;
  a.edit()["speed"] = 2;
  EXPECT_EQ(a->at("speed"), 2);
  EXPECT_EQ(b->at("speed"), 1);
  EXPECT_FALSE(a == b);

  SharedJson empty;
  empty.edit()["x"] = 1;
  EXPECT_TRUE(SharedJson {} -> empty()) << "the shared empty object must never change";
}

TEST(SharedJson, AnEditOfTheOnlyCopyKeepsItsValue) {
  SharedJson a(nlohmann::json{{"speed", 1}});
  const nlohmann::json* before = &*a;
  a.edit()["speed"] = 3;
  EXPECT_EQ(&*a, before);
  EXPECT_EQ(a->at("speed"), 3);
}

TEST(SharedJson, AssignsAJsonValue) {
  SharedJson a;
  a = nlohmann::json{{"card", "ok"}};
  EXPECT_EQ(*a, (nlohmann::json{{"card", "ok"}}));
}

}  // namespace
}  // namespace liftd::api
