// Fuzzes FrameDecoder with arbitrary streams cut into arbitrary pieces.
//
// Input layout: byte 0 picks the limits and how many chunk-size bytes follow (1 to 8); those
// bytes are the sizes the rest of the input is fed in, cycled. Every decoded message must survive
// encode() and a second decode unchanged; anything but a ProtocolError escaping, or a mismatch,
// aborts.
#include "protocol/protocol.hpp"

#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>

namespace {

using bounce::protocol::FrameDecoder;
using bounce::protocol::Limits;
using bounce::protocol::Message;
using bounce::protocol::ProtocolError;

[[noreturn]] void fail(const char* what) {
    std::fprintf(stderr, "decoder_fuzz: %s\n", what);
    std::abort();
}

void check_round_trip(const Message& message) {
    const std::vector<std::uint8_t> frame = bounce::protocol::encode(message);
    // The re-encoded JSON may be longer than what arrived (1e9 comes back as 1000000000.0), so the
    // second decode must not be held to the first one's limits.
    FrameDecoder decoder(Limits{std::numeric_limits<std::uint32_t>::max(),
                                std::numeric_limits<std::uint32_t>::max()});
    decoder.feed(frame);
    const std::optional<Message> again = decoder.next();
    if (!again) {
        fail("an encoded message did not decode");
    }
    if (decoder.next() || decoder.buffered_bytes() != 0) {
        fail("an encoded message left bytes behind");
    }
    if (again->type != message.type || again->request_id != message.request_id ||
        again->attachment != message.attachment) {
        fail("header or attachment changed in a round trip");
    }
    // Compared as serialized text: an overflowing number parses as infinity and is sent as null,
    // which only the serialized forms agree on.
    if (again->body.dump() != message.body.dump()) {
        fail("JSON body changed in a round trip");
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 2) {
        return 0;
    }
    const bool small_limits = (data[0] & 0x80) != 0;
    const std::size_t size_count = std::size_t{data[0] & 0x7u} + 1;
    if (size < 1 + size_count) {
        return 0;
    }
    const std::uint8_t* sizes = data + 1;
    const std::uint8_t* stream = data + 1 + size_count;
    const std::size_t stream_size = size - 1 - size_count;

    FrameDecoder decoder(small_limits ? Limits{64, 64} : Limits{});
    std::size_t fed = 0;
    std::size_t round = 0;
    while (fed < stream_size) {
        // A size byte of 0 feeds everything left, so whole streams are covered as well.
        const std::size_t want = sizes[round++ % size_count];
        const std::size_t chunk = want == 0 ? stream_size - fed : std::min(want, stream_size - fed);
        decoder.feed(std::span<const std::uint8_t>(stream + fed, chunk));
        fed += chunk;
        try {
            while (const std::optional<Message> message = decoder.next()) {
                check_round_trip(*message);
            }
        } catch (const ProtocolError& error) {
            // Poisoned: the same error again, whatever is fed afterwards.
            decoder.feed(std::span<const std::uint8_t>(data, size));
            try {
                decoder.next();
            } catch (const ProtocolError& again) {
                if (again.code != error.code || std::string(again.what()) != error.what() ||
                    again.request_id != error.request_id) {
                    fail("a poisoned decoder threw a different error");
                }
                return 0;
            }
            fail("a poisoned decoder returned normally");
        }
    }
    return 0;
}
