// What the daemon's integration tests share: requests through the client library, error
// expectations, and the Cornell box frame that says a daemon still serves correctly.
#pragma once

#include "daemon_process.hpp"
#include "renderer/image/codec.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace bounce::test {

using client::Client;
using client::ServerError;
using protocol::ErrorCode;
using protocol::MessageType;
using nlohmann::json;

inline const std::string kModels = "/usr/share/assimp/models/glTF2";

// Renders and decodes; expects a frame.
image::DecodedImage render(Client& client, json body);

// Sum of every pixel's red, green and blue.
double rgb_sum(const image::DecodedImage& image);

// Asserts `action` fails with `code` (and `field` when given).
template <typename Action>
void expect_error(Action&& action, ErrorCode code, const std::string& field = "") {
    try {
        action();
        ADD_FAILURE() << "expected error " << protocol::error_code_name(code);
    } catch (const ServerError& error) {
        EXPECT_EQ(error.code(), code) << error.what();
        if (!field.empty()) {
            EXPECT_EQ(error.field().value_or(""), field) << error.what();
        }
    }
}

// The Cornell box as a fresh daemon renders it (EXR, linear): rendering is deterministic, so a
// daemon that still serves correctly reproduces it exactly.
std::vector<float> cornell_frame(const client::Endpoint& endpoint);
void expect_still_serving(const client::Endpoint& endpoint, const std::vector<float>& baseline);

// Reads messages until the reply (ok, frame or error) to `id`; progress events are skipped.
protocol::Message reply_to(Client& client, std::uint64_t id);

std::vector<std::uint8_t> frame_bytes(MessageType type, std::uint64_t id, const json& body,
                                      std::vector<std::uint8_t> attachment = {});

}  // namespace bounce::test
