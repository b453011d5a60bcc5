#include "protocol/protocol.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace bounce::protocol {
namespace {

using nlohmann::json;

std::span<const std::uint8_t, kHeaderSize> header_span(const std::vector<std::uint8_t>& bytes) {
    return std::span<const std::uint8_t, kHeaderSize>(bytes.data(), kHeaderSize);
}

std::vector<std::uint8_t> frame_with_json(std::uint16_t type, std::uint64_t id, const std::string& text,
                                          std::vector<std::uint8_t> attachment = {}) {
    Header header;
    header.type = type;
    header.request_id = id;
    header.json_length = static_cast<std::uint32_t>(text.size());
    header.attachment_length = static_cast<std::uint32_t>(attachment.size());
    std::vector<std::uint8_t> frame(kHeaderSize);
    encode_header(header, frame.data());
    frame.insert(frame.end(), text.begin(), text.end());
    frame.insert(frame.end(), attachment.begin(), attachment.end());
    return frame;
}

// Feeds the whole frame and returns the error next() throws; fails the test when none is thrown.
ProtocolError decode_error(const std::vector<std::uint8_t>& bytes, Limits limits = {}) {
    FrameDecoder decoder(limits);
    decoder.feed(bytes);
    try {
        decoder.next();
    } catch (const ProtocolError& error) {
        return error;
    }
    ADD_FAILURE() << "no ProtocolError thrown";
    return ProtocolError(ErrorCode::internal, "none");
}

void expect_same(const Message& a, const Message& b) {
    EXPECT_EQ(a.type, b.type);
    EXPECT_EQ(a.request_id, b.request_id);
    EXPECT_EQ(a.body, b.body);
    EXPECT_EQ(a.attachment, b.attachment);
}

std::vector<Message> sample_messages() {
    std::vector<std::uint8_t> png(1000);
    for (std::size_t i = 0; i < png.size(); ++i) {
        png[i] = static_cast<std::uint8_t>(i * 7);
    }
    return {
        make_message(MessageType::hello, 1, {{"client", "bounce/0.1"}, {"protocol", 1}}),
        make_message(MessageType::render, 2,
                     {{"scene", "cornell"}, {"width", 256}, {"exposure", -0.5}, {"knobs", {{"a", true}}}}),
        make_message(MessageType::ping, 3),
        make_message(MessageType::frame, 2, {{"format", "png"}}, png),
        make_message(MessageType::scene_load, 0xFFFFFFFFFFFFFFFFull, {{"name", "blob"}},
                     std::vector<std::uint8_t>{0, 1, 2}),
    };
}

std::vector<std::uint8_t> encode_all(const std::vector<Message>& messages) {
    std::vector<std::uint8_t> stream;
    for (const Message& message : messages) {
        const std::vector<std::uint8_t> frame = encode(message);
        stream.insert(stream.end(), frame.begin(), frame.end());
    }
    return stream;
}

TEST(ProtocolHeader, EncodesKnownBytesLittleEndian) {
    Header header;
    header.version = 1;
    header.type = 0x0118;
    header.request_id = 0x0102030405060708ull;
    header.json_length = 0x0A0B0C0D;
    header.attachment_length = 0x11223344;
    const std::array<std::uint8_t, kHeaderSize> expected{
        0x42, 0x4E, 0x43, 0x45,                          // magic "BNCE"
        0x01, 0x00,                                      // version
        0x18, 0x01,                                      // type
        0x08, 0x07, 0x06, 0x05, 0x04, 0x03, 0x02, 0x01,  // request id
        0x0D, 0x0C, 0x0B, 0x0A,                          // JSON length
        0x44, 0x33, 0x22, 0x11,                          // attachment length
    };
    EXPECT_EQ(encode_header(header), expected);

    const Limits unlimited{std::numeric_limits<std::uint32_t>::max(),
                           std::numeric_limits<std::uint32_t>::max()};
    const Header decoded = decode_header(expected, unlimited);
    EXPECT_EQ(decoded.version, 1);
    EXPECT_EQ(decoded.type, 0x0118);
    EXPECT_EQ(decoded.request_id, 0x0102030405060708ull);
    EXPECT_EQ(decoded.json_length, 0x0A0B0C0Du);
    EXPECT_EQ(decoded.attachment_length, 0x11223344u);
}

TEST(ProtocolHeader, DecodeHeaderChecksLimits) {
    const std::vector<std::uint8_t> frame = frame_with_json(24, 77, std::string(100, ' '));
    EXPECT_EQ(decode_header(header_span(frame), Limits{}).json_length, 100u);
    try {
        decode_header(header_span(frame), Limits{99, 0});
        FAIL() << "no throw";
    } catch (const ProtocolError& error) {
        EXPECT_EQ(error.code, ErrorCode::too_large);
        EXPECT_EQ(error.request_id, 77u);
        EXPECT_STREQ(error.what(), "JSON body of 100 bytes exceeds the limit of 99");
    }
}

TEST(ProtocolCodec, RoundTripsMessages) {
    for (const Message& message : sample_messages()) {
        FrameDecoder decoder;
        decoder.feed(encode(message));
        const std::optional<Message> decoded = decoder.next();
        ASSERT_TRUE(decoded);
        expect_same(*decoded, message);
        EXPECT_FALSE(decoder.next());
        EXPECT_EQ(decoder.buffered_bytes(), 0u);
    }
}

TEST(ProtocolCodec, EmptyBodyIsSentAsLengthZero) {
    const std::vector<std::uint8_t> frame = encode(make_message(MessageType::ping, 5));
    ASSERT_EQ(frame.size(), kHeaderSize);
    EXPECT_EQ(frame[16], 0);
    FrameDecoder decoder;
    decoder.feed(frame);
    const std::optional<Message> decoded = decoder.next();
    ASSERT_TRUE(decoded);
    EXPECT_EQ(decoded->body, json::object());
    EXPECT_TRUE(decoded->attachment.empty());

    Message null_body = make_message(MessageType::pong, 6);
    null_body.body = nullptr;
    EXPECT_EQ(encode(null_body).size(), kHeaderSize);
}

TEST(ProtocolCodec, EncodeRefusesNonObjectBody) {
    Message message = make_message(MessageType::ok, 1);
    message.body = json::array({1, 2});
    EXPECT_THROW(encode(message), ProtocolError);
}

TEST(ProtocolDecoder, ByteByByteAndOddChunksGiveTheSameMessages) {
    const std::vector<Message> messages = sample_messages();
    const std::vector<std::uint8_t> stream = encode_all(messages);
    for (const std::size_t chunk : {std::size_t{1}, std::size_t{3}, std::size_t{7}, std::size_t{23},
                                    std::size_t{25}, std::size_t{1001}, stream.size()}) {
        SCOPED_TRACE(chunk);
        FrameDecoder decoder;
        std::vector<Message> decoded;
        for (std::size_t at = 0; at < stream.size(); at += chunk) {
            const std::size_t n = std::min(chunk, stream.size() - at);
            decoder.feed(std::span<const std::uint8_t>(stream.data() + at, n));
            while (std::optional<Message> message = decoder.next()) {
                decoded.push_back(std::move(*message));
            }
        }
        ASSERT_EQ(decoded.size(), messages.size());
        for (std::size_t i = 0; i < messages.size(); ++i) {
            expect_same(decoded[i], messages[i]);
        }
        EXPECT_EQ(decoder.buffered_bytes(), 0u);
    }
}

TEST(ProtocolDecoder, TwoFramesInOneFeed) {
    const Message a = make_message(MessageType::ping, 1);
    const Message b = make_message(MessageType::render, 2, {{"scene", "s"}});
    FrameDecoder decoder;
    decoder.feed(encode_all({a, b}));
    const std::optional<Message> first = decoder.next();
    const std::optional<Message> second = decoder.next();
    ASSERT_TRUE(first && second);
    expect_same(*first, a);
    expect_same(*second, b);
    EXPECT_FALSE(decoder.next());
}

TEST(ProtocolDecoder, TruncatedFrameWaitsForMoreBytes) {
    const std::vector<std::uint8_t> frame =
        encode(make_message(MessageType::frame, 9, {{"w", 1}}, {1, 2, 3}));
    FrameDecoder decoder;
    decoder.feed(std::span<const std::uint8_t>(frame.data(), frame.size() - 1));
    EXPECT_FALSE(decoder.next());
    EXPECT_FALSE(decoder.next());
    EXPECT_EQ(decoder.buffered_bytes(), frame.size() - 1);
    decoder.feed(std::span<const std::uint8_t>(&frame.back(), 1));
    const std::optional<Message> message = decoder.next();
    ASSERT_TRUE(message);
    EXPECT_EQ(message->attachment, (std::vector<std::uint8_t>{1, 2, 3}));
}

TEST(ProtocolDecoder, BadMagicIsBrokenFrame) {
    std::vector<std::uint8_t> frame = encode(make_message(MessageType::ping, 4));
    frame[0] = 'X';
    const ProtocolError error = decode_error(frame);
    EXPECT_EQ(error.code, ErrorCode::broken_frame);
    EXPECT_FALSE(error.request_id);  // nothing in a frame without the magic is trustworthy
    EXPECT_NE(std::string(error.what()).find("magic"), std::string::npos) << error.what();
}

TEST(ProtocolDecoder, WrongVersionIsVersionMismatch) {
    std::vector<std::uint8_t> frame = encode(make_message(MessageType::hello, 12));
    frame[4] = 2;
    const ProtocolError error = decode_error(frame);
    EXPECT_EQ(error.code, ErrorCode::version_mismatch);
    EXPECT_EQ(error.request_id, 12u);
}

TEST(ProtocolDecoder, OversizedJsonIsRefusedFromTheHeaderAlone) {
    Header header;
    header.type = static_cast<std::uint16_t>(MessageType::render);
    header.request_id = 42;
    header.json_length = (1u << 20) + 1;
    FrameDecoder decoder;
    decoder.feed(encode_header(header));  // only the 24 header bytes: no body ever arrives
    try {
        decoder.next();
        FAIL() << "no throw";
    } catch (const ProtocolError& error) {
        EXPECT_EQ(error.code, ErrorCode::too_large);
        EXPECT_EQ(error.request_id, 42u);
        EXPECT_STREQ(error.what(), "JSON body of 1048577 bytes exceeds the limit of 1048576");
    }
}

TEST(ProtocolDecoder, OversizedAttachmentIsRefused) {
    Header header;
    header.request_id = 43;
    header.attachment_length = 300000000;
    FrameDecoder decoder;
    decoder.feed(encode_header(header));
    try {
        decoder.next();
        FAIL() << "no throw";
    } catch (const ProtocolError& error) {
        EXPECT_EQ(error.code, ErrorCode::too_large);
        EXPECT_EQ(error.request_id, 43u);
        EXPECT_STREQ(error.what(), "attachment of 300000000 bytes exceeds the limit of 268435456");
    }
}

TEST(ProtocolDecoder, InvalidJsonIsBrokenFrame) {
    for (const std::string text : {"{\"a\":", "not json", "{} trailing", "{\"s\":\"\xff\xfe\"}"}) {
        SCOPED_TRACE(text);
        const ProtocolError error = decode_error(frame_with_json(24, 8, text));
        EXPECT_EQ(error.code, ErrorCode::broken_frame);
        EXPECT_EQ(error.request_id, 8u);
    }
}

TEST(ProtocolDecoder, NonObjectJsonIsBrokenFrame) {
    for (const std::string text : {"[1,2,3]", "null", "\"text\"", "5"}) {
        SCOPED_TRACE(text);
        const ProtocolError error = decode_error(frame_with_json(24, 8, text));
        EXPECT_EQ(error.code, ErrorCode::broken_frame);
    }
}

TEST(ProtocolDecoder, DeepNestingIsRefusedWithoutCrashing) {
    const ProtocolError arrays = decode_error(frame_with_json(24, 9, std::string(10000, '[')));
    EXPECT_EQ(arrays.code, ErrorCode::broken_frame);
    EXPECT_NE(std::string(arrays.what()).find("nested"), std::string::npos) << arrays.what();

    std::string balanced = "{\"a\":" + std::string(10000, '[') + std::string(10000, ']') + "}";
    EXPECT_EQ(decode_error(frame_with_json(24, 9, balanced)).code, ErrorCode::broken_frame);

    // 64 levels are allowed, 65 are not.
    const std::string at_limit = "{\"a\":" + std::string(63, '[') + std::string(63, ']') + "}";
    EXPECT_EQ(parse_body(std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(at_limit.data()),
                                                       at_limit.size()),
                         1)["a"]
                  .size(),
              1u);
    const std::string past_limit = "{\"a\":" + std::string(64, '[') + std::string(64, ']') + "}";
    EXPECT_THROW(parse_body(std::span<const std::uint8_t>(
                                reinterpret_cast<const std::uint8_t*>(past_limit.data()), past_limit.size()),
                            1),
                 ProtocolError);
}

TEST(ProtocolDecoder, PoisonedAfterAnError) {
    std::vector<std::uint8_t> stream = frame_with_json(24, 10, "[]");
    const std::vector<std::uint8_t> good = encode(make_message(MessageType::ping, 11));
    FrameDecoder decoder;
    decoder.feed(stream);
    EXPECT_THROW(decoder.next(), ProtocolError);
    EXPECT_TRUE(decoder.poisoned());
    decoder.feed(good);
    try {
        decoder.next();
        FAIL() << "a poisoned decoder returned normally";
    } catch (const ProtocolError& error) {
        EXPECT_EQ(error.code, ErrorCode::broken_frame);
        EXPECT_EQ(error.request_id, 10u);
    }
    EXPECT_THROW(decoder.next(), ProtocolError);
}

TEST(ProtocolDecoder, UnknownTypeDecodes) {
    FrameDecoder decoder;
    decoder.feed(frame_with_json(999, 13, "{\"x\":1}"));
    const std::optional<Message> message = decoder.next();
    ASSERT_TRUE(message);
    EXPECT_EQ(message->type, 999);
    EXPECT_FALSE(is_known_message_type(message->type));
    EXPECT_FALSE(message->message_type());
    EXPECT_EQ(message_type_name(message->type), "unknown");
}

TEST(ProtocolDecoder, LargeAttachmentInSmallPieces) {
    std::vector<std::uint8_t> blob(3 << 20);
    for (std::size_t i = 0; i < blob.size(); ++i) {
        blob[i] = static_cast<std::uint8_t>(i ^ (i >> 8));
    }
    const std::vector<std::uint8_t> stream =
        encode_all({make_message(MessageType::scene_load, 1, {{"name", "big"}}, blob),
                    make_message(MessageType::ping, 2)});
    FrameDecoder decoder;
    std::vector<Message> decoded;
    for (std::size_t at = 0; at < stream.size(); at += 1500) {
        const std::size_t n = std::min<std::size_t>(1500, stream.size() - at);
        decoder.feed(std::span<const std::uint8_t>(stream.data() + at, n));
        while (std::optional<Message> message = decoder.next()) {
            decoded.push_back(std::move(*message));
        }
    }
    ASSERT_EQ(decoded.size(), 2u);
    EXPECT_EQ(decoded[0].attachment, blob);
    EXPECT_TRUE(decoded[1].is(MessageType::ping));
}

template <typename F>
FieldError field_error(F&& call) {
    try {
        call();
    } catch (const FieldError& error) {
        return error;
    }
    ADD_FAILURE() << "no FieldError thrown";
    return FieldError("", "");
}

TEST(ProtocolFields, ReadsValidFields) {
    const json body = {{"scene", "cornell"}, {"width", 512}, {"exposure", -1.5}, {"exr_half", true},
                       {"translation", {0.1, 0, 2}}, {"count", 3.0}, {"nothing", nullptr}};
    EXPECT_EQ(get_string(body, "scene"), "cornell");
    EXPECT_EQ(get_integer(body, "width", 1, 16384), 512);
    EXPECT_EQ(get_integer(body, "count", 0, 10), 3);
    EXPECT_DOUBLE_EQ(get_number(body, "exposure"), -1.5);
    EXPECT_EQ(get_optional_bool(body, "exr_half"), true);
    EXPECT_EQ(get_optional_numbers(body, "translation", 3), (std::vector<double>{0.1, 0, 2}));
    EXPECT_FALSE(get_optional_string(body, "tone"));
    EXPECT_FALSE(get_optional_number(body, "nothing"));
    EXPECT_FALSE(get_optional_integer(body, "height", 1, 16384));
    EXPECT_FALSE(get_optional_numbers(body, "matrix", 16));
    EXPECT_EQ(get_integer({{"n", -5}}, "n", -10, -1), -5);
}

TEST(ProtocolFields, ErrorsNameTheFieldAndTheFault) {
    const json body = {{"scene", 3},
                       {"width", 0},
                       {"big", 18446744073709551615ull},
                       {"half", 1.5},
                       {"intensity", std::numeric_limits<double>::infinity()},
                       {"matrix", json::array({1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15})},
                       {"color", {1, "x", 3}},
                       {"flag", "yes"}};
    const auto check = [](const FieldError& error, const std::string& field, const std::string& message) {
        EXPECT_EQ(error.field, field);
        EXPECT_EQ(error.code, ErrorCode::bad_request);
        EXPECT_EQ(std::string(error.what()), message);
    };
    check(field_error([&] { get_string(body, "missing"); }), "missing", "field 'missing' is missing");
    check(field_error([&] { get_string(body, "scene"); }), "scene", "field 'scene' must be a string");
    check(field_error([&] { get_optional_string(body, "scene"); }), "scene",
          "field 'scene' must be a string");
    check(field_error([&] { get_integer(body, "width", 1, 16384); }), "width",
          "field 'width' is 0, outside [1, 16384]");
    check(field_error([&] { get_integer(body, "big", 1, 16384); }), "big",
          "field 'big' is 18446744073709551615, outside [1, 16384]");
    check(field_error([&] { get_optional_integer(body, "half", 0, 10); }), "half",
          "field 'half' must be an integer, got 1.5");
    check(field_error([&] { get_integer(body, "flag", 0, 10); }), "flag", "field 'flag' must be an integer");
    check(field_error([&] { get_number(body, "intensity"); }), "intensity",
          "field 'intensity' is not finite");
    check(field_error([&] { get_optional_number(body, "flag"); }), "flag", "field 'flag' must be a number");
    check(field_error([&] { get_optional_numbers(body, "matrix", 16); }), "matrix",
          "field 'matrix' has 15 numbers, expected 16");
    check(field_error([&] { get_optional_numbers(body, "color", 3); }), "color",
          "field 'color' element 1 is not a number");
    check(field_error([&] { get_optional_numbers(body, "scene", 3); }), "scene",
          "field 'scene' must be an array of 3 numbers");
    check(field_error([&] { get_optional_bool(body, "flag"); }), "flag",
          "field 'flag' must be true or false");
    check(field_error([&] { get_number(json::array(), "x"); }), "x", "field 'x' is missing");
}

TEST(ProtocolReplies, ErrorBodyCarriesCodeMessageFieldAndRetryable) {
    const Message bad = make_error(7, ErrorCode::bad_request, "field 'matrix' has 15 numbers, expected 16",
                                   "matrix");
    EXPECT_TRUE(bad.is(MessageType::error));
    EXPECT_EQ(bad.request_id, 7u);
    EXPECT_EQ(bad.body, (json{{"code", "bad_request"},
                              {"message", "field 'matrix' has 15 numbers, expected 16"},
                              {"field", "matrix"},
                              {"retryable", false}}));

    const Message busy = make_error(8, ErrorCode::busy, "queue full");
    EXPECT_EQ(busy.body["code"], "busy");
    EXPECT_EQ(busy.body["retryable"], true);
    EXPECT_FALSE(busy.body.contains("field"));
    EXPECT_EQ(make_error(9, ErrorCode::timeout, "late").body["retryable"], true);
    EXPECT_EQ(make_error(9, ErrorCode::shutting_down, "bye").body["retryable"], true);
    EXPECT_EQ(make_error(9, ErrorCode::internal, "oops").body["retryable"], false);

    const Message from_field = make_error(10, FieldError("width", "field 'width' is 0, outside [1, 16384]"));
    EXPECT_EQ(from_field.body["field"], "width");
    EXPECT_EQ(from_field.body["code"], "bad_request");

    const Message ok = make_ok(11, {{"scene_version", 3}});
    EXPECT_TRUE(ok.is(MessageType::ok));
    EXPECT_EQ(ok.body["scene_version"], 3);
    EXPECT_EQ(make_ok(12).body, json::object());
}

TEST(ProtocolNames, MessageTypes) {
    const std::vector<std::pair<std::uint16_t, std::string>> table = {
        {1, "hello"},        {2, "ok"},          {3, "error"},          {4, "frame"},
        {5, "progress"},     {6, "ping"},        {7, "pong"},           {8, "cancel"},
        {16, "scene.load"},  {17, "scene.unload"}, {18, "scene.list"},  {19, "scene.describe"},
        {20, "object.set_transform"}, {21, "light.set"}, {22, "light.remove"}, {23, "camera.set"},
        {24, "render"},      {25, "stream.start"}, {26, "stream.stop"}, {27, "bake"},
        {28, "stats"},       {29, "stream.update"},
    };
    for (const auto& [number, name] : table) {
        EXPECT_EQ(message_type_name(number), name);
        EXPECT_TRUE(is_known_message_type(number));
        const std::optional<MessageType> type = message_type_from_name(name);
        ASSERT_TRUE(type) << name;
        EXPECT_EQ(static_cast<std::uint16_t>(*type), number);
    }
    for (const std::uint16_t unknown : {0, 9, 15, 30, 65535}) {
        EXPECT_FALSE(is_known_message_type(unknown));
        EXPECT_EQ(message_type_name(unknown), "unknown");
    }
    EXPECT_FALSE(message_type_from_name("scene_load"));
    EXPECT_EQ(message_type_name(MessageType::light_set), "light.set");
}

TEST(ProtocolNames, ErrorCodes) {
    const std::vector<std::pair<std::string, bool>> table = {
        {"bad_request", false}, {"broken_frame", false}, {"unsupported", false},
        {"version_mismatch", false}, {"unauthorized", false}, {"not_found", false},
        {"too_large", false}, {"busy", true}, {"timeout", true}, {"cancelled", false},
        {"shutting_down", true}, {"internal", false},
    };
    for (const auto& [name, retryable] : table) {
        const std::optional<ErrorCode> code = error_code_from_name(name);
        ASSERT_TRUE(code) << name;
        EXPECT_EQ(error_code_name(*code), name);
        EXPECT_EQ(is_retryable(*code), retryable) << name;
    }
    EXPECT_FALSE(error_code_from_name("nope"));
}

}  // namespace
}  // namespace bounce::protocol
