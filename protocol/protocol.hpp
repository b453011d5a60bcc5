// The Bounce wire format (docs/protocol.md): framing, message and error vocabularies, and the
// request-field checks the daemon and the client share.
//
// Everything here works on bytes and JSON values only: no sockets, no GL, no renderer, so the
// daemon, the client, the tests and the fuzzer can all use the same code.
#pragma once

#include <nlohmann/json.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace bounce::protocol {

inline constexpr std::array<std::uint8_t, 4> kMagic{0x42, 0x4E, 0x43, 0x45};  // "BNCE"
inline constexpr std::uint16_t kProtocolVersion = 1;
inline constexpr std::size_t kHeaderSize = 24;
// Containers nested deeper than this are refused while parsing, before any of it is built:
// a hostile body of nested brackets must not exhaust the stack of later recursive walks.
inline constexpr int kMaxJsonDepth = 64;

enum class MessageType : std::uint16_t {
    hello = 1,
    ok = 2,
    error = 3,
    frame = 4,
    progress = 5,
    ping = 6,
    pong = 7,
    cancel = 8,
    scene_load = 16,
    scene_unload = 17,
    scene_list = 18,
    scene_describe = 19,
    object_set_transform = 20,
    light_set = 21,
    light_remove = 22,
    camera_set = 23,
    render = 24,
    stream_start = 25,
    stream_stop = 26,
    bake = 27,
    stats = 28,
    stream_update = 29,
};

// The wire name ("scene.load"), or "unknown" for a number the table does not have.
std::string_view message_type_name(std::uint16_t type);
inline std::string_view message_type_name(MessageType type) {
    return message_type_name(static_cast<std::uint16_t>(type));
}
std::optional<MessageType> message_type_from_name(std::string_view name);
bool is_known_message_type(std::uint16_t type);

enum class ErrorCode {
    bad_request,
    broken_frame,
    unsupported,
    version_mismatch,
    unauthorized,
    not_found,
    too_large,
    busy,
    timeout,
    cancelled,
    shutting_down,
    internal,
    resource_exhausted,
};

std::string_view error_code_name(ErrorCode code);
std::optional<ErrorCode> error_code_from_name(std::string_view name);
// Whether the same request may succeed if sent again later, unchanged.
bool is_retryable(ErrorCode code);

// A fault in the protocol layer: a broken frame while decoding, or a bad field in a request.
// request_id is set whenever the header could be read, so the receiver can address its error reply.
class ProtocolError : public std::runtime_error {
public:
    ProtocolError(ErrorCode error_code, const std::string& message,
                  std::optional<std::uint64_t> id = std::nullopt)
        : std::runtime_error(message), code(error_code), request_id(id) {}

    ErrorCode code;
    std::optional<std::uint64_t> request_id;
};

// A request field that is missing, of the wrong type or out of range (code bad_request).
class FieldError : public ProtocolError {
public:
    FieldError(std::string field_name, const std::string& message)
        : ProtocolError(ErrorCode::bad_request, message), field(std::move(field_name)) {}

    std::string field;
};

struct Header {
    std::uint16_t version = kProtocolVersion;
    std::uint16_t type = 0;
    std::uint64_t request_id = 0;
    std::uint32_t json_length = 0;
    std::uint32_t attachment_length = 0;
};

struct Limits {
    std::uint32_t max_json_bytes = 1u << 20;
    std::uint32_t max_attachment_bytes = 256u << 20;
};

// Writes the magic and the header fields, little-endian, into exactly kHeaderSize bytes at out.
void encode_header(const Header& header, std::uint8_t* out);
std::array<std::uint8_t, kHeaderSize> encode_header(const Header& header);

// Reads a header and checks it: magic (broken_frame), version (version_mismatch) and both lengths
// against limits (too_large). Nothing of the body is needed, so a reader can refuse a frame
// before allocating for it.
Header decode_header(std::span<const std::uint8_t, kHeaderSize> bytes, const Limits& limits);

// Parses a JSON body: an empty span is {}; anything but one JSON object, invalid UTF-8 or
// nesting deeper than kMaxJsonDepth is a ProtocolError(broken_frame) carrying request_id.
nlohmann::json parse_body(std::span<const std::uint8_t> bytes, std::uint64_t request_id);

struct Message {
    // The raw number, so a frame of a type this side does not know can still be answered.
    std::uint16_t type = 0;
    std::uint64_t request_id = 0;
    nlohmann::json body = nlohmann::json::object();
    std::vector<std::uint8_t> attachment;

    // The type when it is one of the table's, nullopt for an unknown number.
    std::optional<MessageType> message_type() const;
    bool is(MessageType t) const { return type == static_cast<std::uint16_t>(t); }
};

Message make_message(MessageType type, std::uint64_t request_id,
                     nlohmann::json body = nlohmann::json::object(),
                     std::vector<std::uint8_t> attachment = {});

// One complete frame. A null or empty-object body is sent as length 0. Strings that are not valid
// UTF-8 are sent with U+FFFD in place of the bad bytes rather than failing the whole reply.
// Throws ProtocolError(internal) for a body that is not an object and ProtocolError(too_large)
// when the JSON or the attachment does not fit its 32-bit length field.
std::vector<std::uint8_t> encode(const Message& message);

// Splits a byte stream into messages. Feed it whatever arrived; next() returns each complete
// message in order, nullopt while more bytes are needed, and throws ProtocolError for a broken
// frame. After a throw the decoder is poisoned: the stream has lost its framing, so every later
// next() throws the same error again and fed bytes are dropped.
class FrameDecoder {
public:
    explicit FrameDecoder(Limits limits = {});

    void feed(std::span<const std::uint8_t> bytes);
    std::optional<Message> next();

    // Bytes received but not yet returned as messages.
    std::size_t buffered_bytes() const { return buffer_.size() - offset_; }
    bool poisoned() const { return error_.has_value(); }

private:
    [[noreturn]] void poison(const ProtocolError& error);

    Limits limits_;
    std::vector<std::uint8_t> buffer_;
    // Start of the unconsumed bytes; consumed bytes are dropped in bulk so that a frame arriving
    // in many small pieces is not shifted once per piece.
    std::size_t offset_ = 0;
    std::optional<Header> header_;  // of the frame at offset_, once checked
    std::optional<ProtocolError> error_;
};

// Request field checks. Each throws FieldError naming the field and the fault, e.g.
// "field 'width' is 0, outside [1, 16384]". An optional field that is absent or null is nullopt.
std::string get_string(const nlohmann::json& body, std::string_view field);
std::optional<std::string> get_optional_string(const nlohmann::json& body, std::string_view field);
double get_number(const nlohmann::json& body, std::string_view field);  // finite
std::optional<double> get_optional_number(const nlohmann::json& body, std::string_view field);
std::int64_t get_integer(const nlohmann::json& body, std::string_view field, std::int64_t min,
                         std::int64_t max);
std::optional<std::int64_t> get_optional_integer(const nlohmann::json& body, std::string_view field,
                                                 std::int64_t min, std::int64_t max);
bool get_bool(const nlohmann::json& body, std::string_view field);
std::optional<bool> get_optional_bool(const nlohmann::json& body, std::string_view field);
// Exactly count finite numbers.
std::vector<double> get_numbers(const nlohmann::json& body, std::string_view field, std::size_t count);
std::optional<std::vector<double>> get_optional_numbers(const nlohmann::json& body,
                                                        std::string_view field, std::size_t count);

// An error reply: {"code", "message", "field" (when given), "retryable"}.
Message make_error(std::uint64_t request_id, ErrorCode code, std::string message,
                   std::optional<std::string> field = std::nullopt);
// The reply for a caught ProtocolError; a FieldError's field is included.
Message make_error(std::uint64_t request_id, const ProtocolError& error);
Message make_ok(std::uint64_t request_id, nlohmann::json body = nlohmann::json::object());

// The shared token of `hello` (docs/protocol.md, "Authentication"): the first line of a file,
// trailing spaces and CR removed. Throws std::runtime_error naming the file when it cannot be read.
std::string read_token_file(const std::string& path);
// Constant-time comparison, so a wrong token's timing says nothing about the right one.
bool same_token(const std::string& given, const std::string& expected);

}  // namespace bounce::protocol
