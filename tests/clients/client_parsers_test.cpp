// The client's stream parsers, fed in every possible split (the HTTP library's pieces never
// line up with events or parts), plus the tile assembler and the status text.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "clients/api_client.h"
#include "clients/job_view.h"
#include "clients/stream_parsers.h"
#include "clients/tile_assembler.h"
#include "core/image/exr_io.h"

namespace photond::client {
namespace {

std::vector<SseEvent> parse_sse_in_pieces(const std::string& stream, size_t piece) {
    SseParser parser;
    std::vector<SseEvent> events;
    for (size_t i = 0; i < stream.size(); i += piece)
        parser.feed(std::string_view(stream).substr(i, piece), events);
    return events;
}

TEST(SseParser, EventsSurviveEverySplit) {
    const std::string stream =
        ": keep-alive comment\r\n"
        "id: 1\r\nevent: state\r\ndata: {\"state\":\"running\"}\r\n\r\n"
        "id: 2\nevent: progress\ndata: {\"tiles_done\":1,\n"
        "data: \"tiles_total\":4}\n\n"
        "id: 3\revent: done\rdata:{}\r\r"
        "retry: 1500\ndata: plain\n\n";
    for (size_t piece = 1; piece <= stream.size(); ++piece) {
        const std::vector<SseEvent> events = parse_sse_in_pieces(stream, piece);
        ASSERT_EQ(events.size(), 4u) << "piece size " << piece;
        EXPECT_EQ(events[0].type, "state");
        EXPECT_EQ(events[0].id, "1");
        EXPECT_EQ(events[0].data, "{\"state\":\"running\"}");
        EXPECT_EQ(events[1].type, "progress");
        EXPECT_EQ(events[1].data, "{\"tiles_done\":1,\n\"tiles_total\":4}");
        EXPECT_EQ(nlohmann::json::parse(events[1].data)["tiles_total"], 4);
        EXPECT_EQ(events[2].type, "done");
        EXPECT_EQ(events[2].id, "3");
        EXPECT_EQ(events[2].data, "{}");
        // No id line: the last id carries over; no event line: "message".
        EXPECT_EQ(events[3].type, "message");
        EXPECT_EQ(events[3].id, "3");
        EXPECT_EQ(events[3].data, "plain");
        EXPECT_EQ(events[3].retry_ms, 1500);
    }
}

TEST(SseParser, IncompleteEventIsHeldBack) {
    SseParser parser;
    std::vector<SseEvent> events;
    parser.feed("id: 7\nevent: tile\ndata: {}\n", events);
    EXPECT_TRUE(events.empty());
    EXPECT_EQ(parser.last_event_id(), "7");
    parser.feed("\n", events);
    ASSERT_EQ(events.size(), 1u);
    EXPECT_EQ(events[0].type, "tile");
}

TEST(SseParser, EventTypeWithoutDataIsDispatched) {
    SseParser parser;
    std::vector<SseEvent> events;
    parser.feed("event: done\n\n\n", events);
    ASSERT_EQ(events.size(), 1u);
    EXPECT_EQ(events[0].type, "done");
    EXPECT_EQ(events[0].data, "");
}

TEST(MultipartBoundary, ReadsPlainAndQuotedValues) {
    EXPECT_EQ(multipart_boundary("multipart/mixed; boundary=abc123"), "abc123");
    EXPECT_EQ(multipart_boundary("Multipart/Mixed;charset=x; BOUNDARY=\"a b:c\""), "a b:c");
    EXPECT_FALSE(multipart_boundary("image/x-exr; boundary=abc").has_value());
    EXPECT_FALSE(multipart_boundary("multipart/mixed").has_value());
    EXPECT_FALSE(multipart_boundary("multipart/mixed; boundary=").has_value());
}

// A part body holding CR, LF and the boundary text without its leading CRLF, which must not
// end the part.
std::string tricky_body(int n) {
    std::string body = "EXR\r\n-bytes\r\n--tile-boundar" + std::to_string(n) + "\n--tile-boundary";
    body.push_back('\0');
    body += std::string(static_cast<size_t>(n) * 7, char(0xAB));
    return body;
}

std::string multipart_stream(bool with_lengths) {
    std::string stream = "preamble to ignore\r\n";
    for (int n = 0; n < 3; ++n) {
        const std::string body = tricky_body(n);
        stream += "--tile-boundary\r\nContent-Type: image/x-exr\r\nX-Tile-X: " + std::to_string(n) +
                  "\r\nX-Tile-Y: 0\r\nX-Tile-Rect: 0,0,32,32\r\n";
        if (with_lengths) stream += "Content-Length: " + std::to_string(body.size()) + "\r\n";
        stream += "\r\n" + body + "\r\n";
    }
    return stream + "--tile-boundary--\r\nepilogue";
}

TEST(MultipartParser, PartsSurviveEverySplit) {
    for (const bool with_lengths : {false, true}) {
        const std::string stream = multipart_stream(with_lengths);
        for (size_t piece = 1; piece <= stream.size(); ++piece) {
            MultipartParser parser("tile-boundary");
            std::vector<MultipartPart> parts;
            for (size_t i = 0; i < stream.size(); i += piece)
                ASSERT_TRUE(parser.feed(std::string_view(stream).substr(i, piece), parts))
                    << parser.error();
            ASSERT_EQ(parts.size(), 3u) << "piece size " << piece;
            EXPECT_TRUE(parser.finished());
            for (int n = 0; n < 3; ++n) {
                EXPECT_EQ(parts[n].body, tricky_body(n)) << "piece " << piece << " part " << n;
                EXPECT_EQ(parts[n].header("x-tile-x"), std::to_string(n));
                EXPECT_EQ(parts[n].header("X-Tile-Rect"), "0,0,32,32");
                EXPECT_EQ(parts[n].header("content-type"), "image/x-exr");
            }
        }
    }
}

TEST(MultipartParser, StreamStartingWithDelimiterAndWithoutEnd) {
    MultipartParser parser("b");
    std::vector<MultipartPart> parts;
    ASSERT_TRUE(parser.feed("--b\r\nX-Tile-X: 1\r\n\r\nabc\r\n--b\r\n\r\nsecond", parts));
    ASSERT_EQ(parts.size(), 1u);
    EXPECT_EQ(parts[0].body, "abc");
    EXPECT_FALSE(parser.finished());  // the second part is still open
}

TEST(MultipartParser, WrongContentLengthIsAnError) {
    MultipartParser parser("b");
    std::vector<MultipartPart> parts;
    EXPECT_FALSE(parser.feed("--b\r\nContent-Length: 2\r\n\r\nabc\r\n--b--\r\n", parts));
    EXPECT_NE(parser.error().find("Content-Length"), std::string::npos);
    EXPECT_TRUE(parts.empty());
}

TEST(ServerUrl, SplitsOriginAndPrefix) {
    Expected<ServerUrl> plain = parse_server_url("http://127.0.0.1:8080");
    ASSERT_TRUE(plain) << plain.error().message;
    EXPECT_EQ(plain->origin, "http://127.0.0.1:8080");
    EXPECT_EQ(plain->path_prefix, "");
    Expected<ServerUrl> prefixed = parse_server_url("localhost:9000/render/");
    ASSERT_TRUE(prefixed) << prefixed.error().message;
    EXPECT_EQ(prefixed->origin, "http://localhost:9000");
    EXPECT_EQ(prefixed->path_prefix, "/render");
    EXPECT_FALSE(parse_server_url("ftp://host:1"));
    EXPECT_EQ(encode_path_segment("ab/c d"), "ab%2Fc%20d");
}

TEST(Problem, ProblemJsonAndPlainBodies) {
    const Problem problem =
        parse_problem(422, "application/problem+json",
                      R"({"type":"about:blank","title":"invalid job","status":422,)"
                      R"("detail":"image.sppp: unknown field","field":"image.sppp"})");
    EXPECT_EQ(describe(problem), "invalid job: image.sppp: unknown field (field: image.sppp)");
    const Problem plain = parse_problem(502, "text/html", "<h1>bad\ngateway</h1>\n");
    EXPECT_EQ(describe(plain), "Bad Gateway (HTTP 502): <h1>bad gateway</h1>");
}

TEST(JobView, StatusTextAndProgress) {
    const nlohmann::json status = nlohmann::json::parse(R"({
        "id": "j1", "state": "running",
        "job": {"scene": {"builtin": "cornell-box"}, "preset": "preview",
                "image": {"width": 64, "height": 48, "spp": 2}},
        "progress": {"tiles_done": 3, "tiles_total": 4, "fraction": 0.75},
        "photons": {"cache": "hit"},
        "timings": {"render": 1.5, "photon_tracing": 0.0, "custom": 2},
        "plan": [{"pass": "caustic_map", "enabled": false, "reason": "no specular surface"}],
        "error": {"title": "render failed", "detail": "out of memory"}})");
    const std::string text = format_status(status);
    for (const char* expected :
         {"job       j1\n", "state     running\n", "scene     builtin:cornell-box\n",
          "image     64x48, 2 spp\n", "progress  3/4 tiles (75%)\n", "photons   cache hit\n",
          "timings   photon_tracing 0.00 s, render 1.50 s, custom 2.00 s\n",
          "plan      caustic_map: skipped (no specular surface)\n",
          "error     render failed: out of memory\n"}) {
        EXPECT_NE(text.find(expected), std::string::npos) << expected << "\nin\n" << text;
    }
    const auto progress = read_progress(status);
    ASSERT_TRUE(progress.has_value());
    EXPECT_EQ(progress_bar(*progress, 8), "[######--]  75%  3/4 tiles");
    EXPECT_TRUE(is_terminal_state("cancelled"));
    EXPECT_FALSE(is_terminal_state("running"));

    const std::string list = format_job_list(nlohmann::json::array({status}));
    EXPECT_EQ(list, "ID  STATE    PROGRESS  SCENE\nj1  running  75%       builtin:cornell-box\n");
}

ImageLayers gradient(int width, int height) {
    ImageLayers layers;
    layers.beauty = Image(width, height);
    Image direct(width, height);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            layers.beauty.at(x, y) = Color(float(x) * 0.25f, float(y) * 0.5f, 1.0f);
            direct.at(x, y) = Color(float(x + y));
        }
    layers.aovs.emplace_back("direct", direct);
    return layers;
}

TEST(TileAssembler, TilesInAnyOrderGiveTheFrame) {
    const ImageLayers frame = gradient(40, 24);
    const std::vector<PixelRect> rects{{32, 16, 40, 24}, {0, 0, 16, 16},  {16, 0, 32, 16},
                                       {32, 0, 40, 16},  {0, 16, 16, 24}, {16, 16, 32, 24}};
    TileAssembler assembler;
    for (const PixelRect& rect : rects) {
        Expected<std::vector<uint8_t>> bytes =
            encode_tile_exr(copy_rect(frame, rect), rect, 40, 24, ExrPixelType::Float);
        ASSERT_TRUE(bytes) << bytes.error().message;
        ASSERT_TRUE(assembler.add_tile(*bytes).is_ok());
        ASSERT_TRUE(assembler.add_tile(*bytes).is_ok());  // a resent tile replaces its copy
    }
    EXPECT_EQ(assembler.tile_count(), 6);
    EXPECT_EQ(assembler.largest_tile_edge(), 16);
    EXPECT_EQ(assembler.frame().beauty, frame.beauty);
    ASSERT_NE(assembler.frame().find_aov("direct"), nullptr);
    EXPECT_EQ(*assembler.frame().find_aov("direct"), frame.aovs[0].second);

    Expected<std::vector<uint8_t>> other = encode_tile_exr(copy_rect(gradient(8, 8), {0, 0, 8, 8}),
                                                           {0, 0, 8, 8}, 8, 8, ExrPixelType::Half);
    ASSERT_TRUE(other);
    EXPECT_FALSE(assembler.add_tile(*other).is_ok());  // another frame size
    const std::vector<uint8_t> garbage{1, 2, 3};
    EXPECT_FALSE(assembler.add_tile(garbage).is_ok());
}

}  // namespace
}  // namespace photond::client
