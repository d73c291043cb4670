#include <array>
#include <catch2/catch.hpp>

#include "prt/params.hpp"
#include "prt/plugin.hpp"

using namespace prt;

namespace {
ParamSchema test_schema() {
  return {"basis \"sh\"",
          {schema::integer("order", "6", 1, 30, "bands"),
           schema::real("window", "0.5", 0, 1, "window strength"),
           schema::choice("kind", "hanning", "hanning|lanczos", "window kind"),
           schema::reals("albedo", "0.8", 3, 0, 1, "colour"),
           schema::boolean("fast", "false", "speed switch")}};
}
SourceLocation at(int line, int column) {
  return {"scene.toml", line, column};
}
}  // namespace

TEST_CASE("edit distance and did-you-mean", "[params]") {
  CHECK(edit_distance("order", "order") == 0);
  CHECK(edit_distance("ordr", "order") == 1);
  CHECK(edit_distance("", "abc") == 3);
  CHECK(closest_match("ordr", {"order", "window"}) == "order");
  CHECK(closest_match("zzzzzz", {"order", "window"}).empty());
}

TEST_CASE("defaults are filled and typed getters read them", "[params]") {
  Params p(at(1, 1));
  p.validate(test_schema());
  CHECK(p.get_int("order") == 6);
  CHECK(p.get_real("window") == 0.5);
  CHECK(p.get_string("kind") == "hanning");
  CHECK(p.get_reals("albedo") == std::vector<double>{0.8, 0.8, 0.8});
  CHECK_FALSE(p.get_bool("fast"));
}

TEST_CASE("an unknown key names the place, the valid keys and the closest one", "[params]") {
  Params p(at(1, 1));
  p.set("ordr", std::int64_t(10), at(14, 9));
  try {
    p.validate(test_schema());
    FAIL("no error");
  } catch (const Error& e) {
    CHECK(std::string(e.what()) ==
          "scene.toml:14:9: error: basis \"sh\": unknown parameter \"ordr\"; valid: order, "
          "window, kind, albedo, fast (did you mean \"order\"?)");
  }
}

TEST_CASE("wrong types, ranges and choices are rejected with the location", "[params]") {
  auto fails_with = [](const std::string& key, ParamValue value, const std::string& fragment) {
    Params p(at(1, 1));
    p.set(key, std::move(value), at(3, 5));
    REQUIRE_THROWS_WITH(p.validate(test_schema()),
                        Catch::Contains("scene.toml:3:5") && Catch::Contains(fragment));
  };
  fails_with("order", std::string("ten"), "must be an integer");
  fails_with("order", 2.5, "must be an integer");
  fails_with("order", std::int64_t(31), "out of range [1, 30]");
  fails_with("order", std::int64_t(0), "out of range");
  fails_with("window", std::string("x"), "must be a real");
  fails_with("kind", std::string("hamming"), "did you mean \"hanning\"");
  fails_with("albedo", std::vector<double>{1, 1}, "list of 3");
  fails_with("albedo", std::vector<double>{1, 2, 1}, "out of range");
  fails_with("fast", std::int64_t(1), "must be a bool");
}

TEST_CASE("integers are accepted for reals and scalars broadcast to lists", "[params]") {
  Params p(at(1, 1));
  p.set("window", std::int64_t(1));
  p.set("albedo", 0.25);
  p.validate(test_schema());
  CHECK(p.get_real("window") == 1.0);
  CHECK(p.get_reals("albedo") == std::vector<double>{0.25, 0.25, 0.25});
}

TEST_CASE("a required parameter that is missing is an error", "[params]") {
  ParamSchema s{"section [mesh]", {schema::path("file", true, "mesh file")}};
  Params p(at(2, 1));
  REQUIRE_THROWS_WITH(p.validate(s), Catch::Contains("missing required parameter \"file\"") &&
                                         Catch::Contains("scene.toml:2:1"));
}
