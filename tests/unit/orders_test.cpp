// Requests parsed into orders on the network thread: each documented range (docs/protocol.md,
// "Numbers") holds at its edge and refuses just past it, naming the field; the byte budget that
// request bodies are read under never hands out more than its limit.
#include "server/byte_budget.hpp"
#include "server/orders.hpp"
#include "server/request_error.hpp"

#include <gtest/gtest.h>

namespace bounce::server {
namespace {

using nlohmann::json;
using protocol::MessageType;

Order parse(MessageType type, json body) {
    return parse_order({static_cast<std::uint16_t>(type), 1, std::move(body), {}}, 4096ull * 4096ull);
}

// The field a refusal names, or "" when the order parsed.
std::string refused_field(MessageType type, json body) {
    try {
        parse(type, std::move(body));
    } catch (...) {
        return describe_failure(std::current_exception()).field.value_or("(no field)");
    }
    return "";
}

// A method, preset or knob the registry does not know is refused naming that field.
TEST(Orders, UnknownMethodPresetAndKnobNameTheirField) {
    const json render = {{"scene", "s"}};
    EXPECT_EQ(refused_field(MessageType::render, render), "");
    EXPECT_EQ(refused_field(MessageType::render, {{"scene", "s"}, {"method", "magic"}}), "method");
    EXPECT_EQ(refused_field(MessageType::render, {{"scene", "s"}, {"method", "vct"}, {"preset", "best"}}), "preset");
    EXPECT_EQ(refused_field(MessageType::render, {{"scene", "s"}, {"knobs", {{"bogus", 1}}}}), "knobs");
    EXPECT_EQ(refused_field(MessageType::render, {{"scene", "s"}, {"method", "vct"}, {"knobs", {{"resolution", 1e9}}}}),
              "knobs");
}

TEST(Orders, NumbersHoldAtTheirDocumentedEdgesAndAreRefusedPastThem) {
    const json transform = {{"scene", "s"}, {"object", "o"}};
    auto with = [](json body, const char* field, json value) {
        body[field] = std::move(value);
        return body;
    };
    EXPECT_EQ(refused_field(MessageType::object_set_transform, with(transform, "translation", {1e7, -1e7, 0})), "");
    EXPECT_EQ(refused_field(MessageType::object_set_transform, with(transform, "translation", {1.01e7, 0, 0})),
              "translation");
    EXPECT_EQ(refused_field(MessageType::object_set_transform, with(transform, "translation", {1e39, 0, 0})),
              "translation");
    EXPECT_EQ(refused_field(MessageType::object_set_transform, with(transform, "rotation_deg", {1e6, 0, 0})), "");
    EXPECT_EQ(refused_field(MessageType::object_set_transform, with(transform, "rotation_deg", {2e6, 0, 0})),
              "rotation_deg");
    EXPECT_EQ(refused_field(MessageType::object_set_transform, with(transform, "scale", 1e6)), "");
    EXPECT_EQ(refused_field(MessageType::object_set_transform, with(transform, "scale", 1e-6)), "");
    EXPECT_EQ(refused_field(MessageType::object_set_transform, with(transform, "scale", 0)), "scale");
    EXPECT_EQ(refused_field(MessageType::object_set_transform, with(transform, "scale", 1e-300)), "scale");
    json matrix = json::array();
    for (int i = 0; i < 16; ++i) matrix.push_back(i == 12 ? 2e7 : 1.0);
    EXPECT_EQ(refused_field(MessageType::object_set_transform, with(transform, "matrix", matrix)), "matrix");
    EXPECT_EQ(refused_field(MessageType::object_set_transform, transform), "matrix");  // nothing to set

    const json light = {{"scene", "s"}, {"light", "l"}};
    EXPECT_EQ(refused_field(MessageType::light_set, with(light, "position", {0, 1e7, 0})), "");
    EXPECT_EQ(refused_field(MessageType::light_set, with(light, "position", {0, 1e39, 0})), "position");
    EXPECT_EQ(refused_field(MessageType::light_set, with(light, "direction", {0, 0, 0})), "direction");
    EXPECT_EQ(refused_field(MessageType::light_set, with(light, "color", {1e6, 0, 0})), "");
    EXPECT_EQ(refused_field(MessageType::light_set, with(light, "color", {2e6, 0, 0})), "color");
    EXPECT_EQ(refused_field(MessageType::light_set, with(light, "color", {-0.1, 0, 0})), "color");
    EXPECT_EQ(refused_field(MessageType::light_set, with(light, "intensity", 1e12)), "");
    EXPECT_EQ(refused_field(MessageType::light_set, with(light, "intensity", 1e13)), "intensity");
    EXPECT_EQ(refused_field(MessageType::light_set, with(light, "outer_cone_deg", 90)), "");
    EXPECT_EQ(refused_field(MessageType::light_set, with(light, "outer_cone_deg", 91)), "outer_cone_deg");

    const json camera = {{"scene", "s"}};
    EXPECT_EQ(refused_field(MessageType::camera_set, with(camera, "fov_deg", 178.9)), "");
    EXPECT_EQ(refused_field(MessageType::camera_set, with(camera, "fov_deg", 179)), "fov_deg");
    EXPECT_EQ(refused_field(MessageType::camera_set, with(camera, "orientation", {0, 0, 0, 0})), "orientation");
    EXPECT_EQ(refused_field(MessageType::camera_set, with(camera, "look_at", {0, 0, 2e7})), "look_at");

    const json render = {{"scene", "s"}};
    EXPECT_EQ(refused_field(MessageType::render, with(render, "exposure", 64)), "");
    EXPECT_EQ(refused_field(MessageType::render, with(render, "exposure", 65)), "exposure");
    EXPECT_EQ(refused_field(MessageType::render, with(render, "width", 0)), "width");
    EXPECT_EQ(refused_field(MessageType::render, with(render, "knobs", {{"spp", 1}})), "knobs");  // not direct's
}

TEST(Orders, RendersArePlannedAndBakesOfCpuMethodsRefused) {
    const Order render = parse(MessageType::render, {{"scene", "s"}, {"method", "reference"}, {"preset", "draft"}});
    const auto& order = std::get<RenderOrder>(render);
    EXPECT_EQ(order.plan.site, FrameSite::cpu);
    EXPECT_EQ(order.plan.knobs.at("spp"), 4.0);
    EXPECT_EQ(refused_field(MessageType::bake, {{"scene", "s"}, {"method", "reference"}}), "method");
    EXPECT_EQ(refused_field(MessageType::scene_load, {{"name", "s"}}), "path");  // no path, builtin or upload
    EXPECT_EQ(refused_field(MessageType::scene_load, {{"name", "s"}, {"builtin", "cornell"}, {"dynamic", "x"}}),
              "dynamic");
}

TEST(ByteBudget, NeverHandsOutMoreThanItsLimitAndReservationsGiveBack) {
    ByteBudget budget(1000);
    {
        ByteBudget::Reservation a(budget), b(budget);
        EXPECT_TRUE(a.grow(600));
        EXPECT_FALSE(b.grow(401));  // 1001 would pass the limit
        EXPECT_EQ(b.bytes(), 0u);
        EXPECT_TRUE(b.grow(400));
        EXPECT_EQ(budget.used(), 1000u);
        EXPECT_FALSE(a.grow(1));
        ByteBudget::Reservation moved = std::move(a);
        EXPECT_EQ(a.bytes(), 0u);
        EXPECT_EQ(moved.bytes(), 600u);
        EXPECT_EQ(budget.used(), 1000u);
        moved.release();
        EXPECT_EQ(budget.used(), 400u);
        EXPECT_FALSE(ByteBudget::Reservation().grow(1));  // no budget: nothing
        EXPECT_FALSE(moved.grow(std::numeric_limits<std::size_t>::max()));  // no wrap-around
    }
    EXPECT_EQ(budget.used(), 0u);  // destructors gave the rest back
}

}  // namespace
}  // namespace bounce::server
