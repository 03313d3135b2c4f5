/*
 * How a C++ renderer connects: the loop of a renderer that draws nothing, over the C library
 * through its C++17 wrapper (vas_client.hpp). It prints what client-rs/examples/renderer.rs
 * prints, in the same words and numbers: the scene's meshes once per scene generation, then for
 * each new state a line per part and, for each hand with a new frame, a line for the hand and
 * one per segment, naming the hand's user (the scene info names the users).
 *
 *   c++ -std=c++17 -Iclient-c/include client-c/examples/renderer.cpp -Ltarget/release \
 *       -lvas_client -o renderer
 *   LD_LIBRARY_PATH=target/release ./renderer --prefix demo --frames 20
 */
#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "vas_client.hpp"

namespace {

/// A float as Rust's `{:?}` writes it: the shortest digits that read back as the same value
/// (a tie between two such broken upwards), in decimal with at least one fractional digit, or
/// as `1.5e-7` below 1e-4 and from 1e16 on. The renderers of every language print the same text.
template <typename Float>
std::string rust_debug(Float value) {
    if (std::isnan(value)) {
        return "NaN";
    }
    std::string sign = std::signbit(value) ? "-" : "";
    Float magnitude = std::fabs(value);
    if (std::isinf(magnitude)) {
        return sign + "inf";
    }
    if (magnitude == 0) {
        return sign + "0.0";
    }
    // The shortest digits d.ddd and their exponent, from to_chars.
    char buffer[1100];
    auto shortest = std::to_chars(buffer, buffer + sizeof buffer, magnitude,
                                  std::chars_format::scientific);
    std::string text(buffer, shortest.ptr);
    std::size_t e = text.find('e');
    int exponent = std::atoi(text.c_str() + e + 1);
    std::string digits = text.substr(0, 1) + (e > 1 ? text.substr(2, e - 2) : "");
    // to_chars breaks a tie to even, Rust upwards: a tie is an exact value one digit longer,
    // ending in 5, whose other digits are the shortest ones.
    auto exact = std::to_chars(buffer, buffer + sizeof buffer, magnitude,
                               std::chars_format::scientific, 1000);
    std::string all(buffer, exact.ptr);
    std::string exact_digits = all.substr(0, 1) + all.substr(2, all.find('e') - 2);
    exact_digits.erase(exact_digits.find_last_not_of('0') + 1);
    if (exact_digits.size() == digits.size() + 1 && exact_digits.back() == '5' &&
        exact_digits.compare(0, digits.size(), digits) == 0) {
        std::size_t at = digits.size();
        while (at > 0 && digits[at - 1] == '9') {
            digits[--at] = '0';
        }
        if (at == 0) {
            digits.insert(digits.begin(), '1');
            digits.pop_back();
            ++exponent;
        } else {
            ++digits[at - 1];
        }
        digits.erase(std::max<std::size_t>(1, digits.find_last_not_of('0') + 1));
    }
    if (magnitude < Float(1e-4) || magnitude >= Float(1e16)) {
        std::string mantissa = digits.substr(0, 1);
        if (digits.size() > 1) {
            mantissa += "." + digits.substr(1);
        }
        return sign + mantissa + "e" + std::to_string(exponent);
    }
    if (exponent < 0) {
        return sign + "0." + std::string(static_cast<std::size_t>(-exponent - 1), '0') + digits;
    }
    std::size_t integer = static_cast<std::size_t>(exponent) + 1;
    if (digits.size() <= integer) {
        return sign + digits + std::string(integer - digits.size(), '0') + ".0";
    }
    return sign + digits.substr(0, integer) + "." + digits.substr(integer);
}

/// An array of floats as Rust's `{:?}` writes it: `[1.0, -0.5, 2e-5]`.
template <typename Float, std::size_t N>
std::string rust_debug(const Float (&values)[N]) {
    std::string text = "[";
    for (std::size_t i = 0; i < N; ++i) {
        text += (i == 0 ? "" : ", ") + rust_debug(values[i]);
    }
    return text + "]";
}

/// A string as Rust's `{:?}` writes it: quoted, with quotes, backslashes and control
/// characters escaped.
std::string rust_debug(std::string_view value) {
    std::string text = "\"";
    for (char c : value) {
        switch (c) {
            case '"': text += "\\\""; break;
            case '\\': text += "\\\\"; break;
            case '\n': text += "\\n"; break;
            case '\r': text += "\\r"; break;
            case '\t': text += "\\t"; break;
            case '\0': text += "\\0"; break;
            default:
                if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
                    char escaped[16];
                    std::snprintf(escaped, sizeof escaped, "\\u{%x}", static_cast<unsigned>(c));
                    text += escaped;
                } else {
                    text += c;
                }
        }
    }
    return text + "\"";
}

/// The smallest and largest coordinates of a mesh's positions; zeros without positions.
void bounds(const VasMesh& mesh, float (&min)[3], float (&max)[3]) {
    auto positions = vas::positions(mesh);
    for (int axis = 0; axis < 3; ++axis) {
        min[axis] = positions.empty() ? 0.0f : positions[0][axis];
        max[axis] = min[axis];
        for (const auto& position : positions) {
            min[axis] = std::fmin(min[axis], position[axis]);
            max[axis] = std::fmax(max[axis], position[axis]);
        }
    }
}

/// The command line: --prefix and --frames, as the Rust example takes them.
struct Args {
    std::optional<std::string> prefix;
    std::optional<uint64_t> frames;
};

std::optional<Args> parse_args(int argc, char** argv) {
    Args args;
    for (int i = 1; i < argc; ++i) {
        std::string_view flag = argv[i];
        if (i + 1 == argc) {
            return std::nullopt;
        }
        std::string_view value = argv[++i];
        if (flag == "--prefix") {
            args.prefix = std::string(value);
        } else if (flag == "--frames") {
            uint64_t frames = 0;
            auto parsed = std::from_chars(value.data(), value.data() + value.size(), frames);
            if (parsed.ec != std::errc() || parsed.ptr != value.data() + value.size()) {
                return std::nullopt;
            }
            args.frames = frames;
        } else {
            return std::nullopt;
        }
    }
    return args;
}

/// Prints every part's mesh: once per scene generation, where a renderer uploads them.
void print_meshes(const VasGeometry& geometry) {
    uint64_t id = 0;
    for (const VasMesh& mesh : vas::parts(geometry)) {
        float min[3], max[3];
        bounds(mesh, min, max);
        std::cout << "mesh part=" << id++ << " name=" << rust_debug(vas::text(mesh.name))
                  << " triangles=" << mesh.triangle_count << " min=" << rust_debug(min)
                  << " max=" << rust_debug(max) << '\n';
    }
}

/// Prints a hand's line and a line per segment, each naming the hand's user and side: each
/// segment's mesh goes where the server verified the segment, with no kinematics here.
void print_hand(const VasSceneInfo& scene, const VasHandFrame& hand, std::string_view side) {
    std::string user = rust_debug(
        std::string_view(hand.user < scene.user_count ? scene.users[hand.user] : "?"));
    std::string_view grasp = vas::name_of(vas_grasp_type_name(hand.grasp_type)).value_or("unknown");
    std::cout << "hand frame=" << hand.frame << " user=" << user << " side=" << side
              << " grasp=" << grasp << " position=" << rust_debug(hand.root.position) << '\n';
    uint32_t index = 0;
    for (const VasWirePose& pose : vas::segment_poses(hand)) {
        std::cout << "segment frame=" << hand.frame << " user=" << user << " side=" << side
                  << " name=" << vas::text(vas_hand_segment_name(index++))
                  << " position=" << rust_debug(pose.position)
                  << " rotation=" << rust_debug(pose.rotation) << '\n';
    }
}

int run(const Args& args) {
    // With the signals handled, Ctrl-C ends the loop below and the client leaves cleanly.
    vas::Client client = vas::Client::connect(args.prefix ? args.prefix->c_str() : nullptr,
                                              VAS_ROLE_RENDER, true);
    // What was drawn last: a renderer redraws when the newest state differs, whichever poll
    // brought it; each hand (by user and side) has its own.
    uint64_t drawn = 0;
    std::optional<uint64_t> generation, parts_frame;
    std::map<std::pair<uint32_t, uint32_t>, uint64_t> hand_frames;
    const VasSceneInfo* scene = nullptr;  // The users' names, asked for with each scene's meshes.
    while (!args.frames || drawn < *args.frames) {
        VasWake wake = client.wait(std::chrono::seconds(1));
        if (wake == VAS_WAKE_TIMEOUT) {
            continue;
        }
        if (wake == VAS_WAKE_TERMINATED) {
            break;
        }
        client.poll();
        const VasGeometry* geometry = client.geometry();
        if (geometry == nullptr) {
            continue;  // Nothing to draw before the meshes.
        }
        if (generation != geometry->generation) {
            generation = geometry->generation;
            print_meshes(*geometry);
            scene = &client.scene_info(std::chrono::seconds(5));
        }
        std::optional<vas::PartsFrame> parts = client.latest_parts();
        if (parts && parts_frame == parts->header.frame) {
            parts.reset();
        }
        std::vector<std::pair<std::string_view, const VasHandFrame*>> hands;
        for (const VasHandFrame& hand : client.latest_hands()) {
            auto side = vas::name_of(vas_hand_side_name(hand.hand));
            auto last = hand_frames.find({hand.user, hand.hand});
            if (side && (last == hand_frames.end() || last->second != hand.frame)) {
                hands.emplace_back(*side, &hand);
            }
        }
        if (!parts && hands.empty()) {
            continue;  // Events or force frames alone draw nothing.
        }
        ++drawn;
        if (parts) {
            parts_frame = parts->header.frame;
            auto meshes = vas::parts(*geometry);
            for (const VasPartState& part : parts->parts) {
                std::string_view name =
                    part.id < meshes.size() ? vas::text(meshes[part.id].name) : "?";
                std::cout << "part frame=" << parts->header.frame << " id=" << part.id
                          << " name=" << rust_debug(name)
                          << " position=" << rust_debug(part.position)
                          << " rotation=" << rust_debug(part.rotation) << '\n';
            }
        }
        for (const auto& [side, hand] : hands) {
            hand_frames[{hand->user, hand->hand}] = hand->frame;
            print_hand(*scene, *hand, side);
        }
        // Each drawn frame reaches a pipe at once, as the Rust example's lines do.
        std::cout.flush();
    }
    return EXIT_SUCCESS;
}

}  // namespace

int main(int argc, char** argv) {
    std::optional<Args> args = parse_args(argc, argv);
    if (!args) {
        std::cerr << "usage: renderer [--prefix PREFIX] [--frames N]\n";
        return 2;
    }
    try {
        return run(*args);
    } catch (const vas::Error& error) {
        std::cerr << "renderer: " << error.what() << '\n';
        return EXIT_FAILURE;
    }
}
