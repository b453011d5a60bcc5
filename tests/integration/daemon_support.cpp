#include "daemon_support.hpp"

namespace bounce::test {

image::DecodedImage render(Client& client, json body) {
    const auto reply = client.request(MessageType::render, std::move(body));
    EXPECT_EQ(reply.type, static_cast<std::uint16_t>(MessageType::frame));
    return image::decode_image(reply.attachment);
}

double rgb_sum(const image::DecodedImage& image) {
    double sum = 0.0;
    for (std::size_t i = 0; i < image.pixels.size(); ++i) {
        if (i % 4 != 3) sum += image.pixels[i];
    }
    return sum;
}

std::vector<float> cornell_frame(const client::Endpoint& endpoint) {
    Client client(endpoint);
    return render(client, {{"scene", "cornell"}, {"width", 32}, {"height", 32}, {"format", "exr"}}).pixels;
}

void expect_still_serving(const client::Endpoint& endpoint, const std::vector<float>& baseline) {
    const auto now = cornell_frame(endpoint);
    ASSERT_EQ(now.size(), baseline.size());
    EXPECT_TRUE(now == baseline) << "the Cornell box frame changed after bad input";
}

protocol::Message reply_to(Client& client, std::uint64_t id) {
    for (;;) {
        auto message = client.read();
        if (message.request_id == id && message.type != static_cast<std::uint16_t>(MessageType::progress)) return message;
    }
}

std::vector<std::uint8_t> frame_bytes(MessageType type, std::uint64_t id, const json& body,
                                      std::vector<std::uint8_t> attachment) {
    return protocol::encode({static_cast<std::uint16_t>(type), id, body, std::move(attachment)});
}

}  // namespace bounce::test
