/*
 * vas_client.hpp: a C++17 wrapper over the vas C library (vas_client.h), header only.
 *
 * vas::Client owns a connection: it frees it when it goes out of scope, moves but never copies
 * (a connection belongs to the thread that made it), and throws vas::Error when a call fails,
 * with the library's status and message. Frames and meshes are vas::View's over the library's
 * own memory, valid as long as vas_client.h says for the pointer behind them (parts and hands
 * until the next poll, geometry until another generation arrives, events until the next take).
 */
#ifndef VAS_CLIENT_HPP
#define VAS_CLIENT_HPP

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <iterator>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

#include "vas_client.h"

namespace vas {

/// A read-only view of `size` consecutive elements that the library owns (std::span is C++20).
template <typename T>
class View {
public:
    View() = default;
    View(const T* data, std::size_t size) : data_(size == 0 ? nullptr : data), size_(size) {}

    const T* begin() const noexcept { return data_; }
    const T* end() const noexcept { return data_ + size_; }
    std::size_t size() const noexcept { return size_; }
    bool empty() const noexcept { return size_ == 0; }
    const T& operator[](std::size_t index) const noexcept { return data_[index]; }

private:
    const T* data_ = nullptr;
    std::size_t size_ = 0;
};

/// A failed call: the library's status and the words of vas_last_error_message().
class Error : public std::runtime_error {
public:
    Error(VasStatus status, const std::string& message)
        : std::runtime_error(message), status_(status) {}

    VasStatus status() const noexcept { return status_; }

private:
    VasStatus status_;
};

/// Throws an Error for a failed `action`; otherwise whether there was something to give (Ok)
/// rather than nothing yet (Empty).
inline bool check(VasStatus status, const char* action) {
    if (status == VAS_STATUS_OK || status == VAS_STATUS_EMPTY) {
        return status == VAS_STATUS_OK;
    }
    throw Error(status, std::string("cannot ") + action + ": " + vas_last_error_message());
}

/// The newest parts frame: its header and every part's pose and state, indexed by part id.
struct PartsFrame {
    VasPartsFrameHeader header;
    View<VasPartState> parts;
};

/// A NUL-terminated string of the library as a view; empty for null.
inline std::string_view text(const char* string) {
    return string == nullptr ? std::string_view() : std::string_view(string);
}

/// A code's name from one of the library's name functions; none for a code it does not know.
inline std::optional<std::string_view> name_of(const char* name) {
    if (name == nullptr) {
        return std::nullopt;
    }
    return std::string_view(name);
}

inline View<VasMesh> parts(const VasGeometry& geometry) {
    return {geometry.parts, geometry.part_count};
}
inline View<VasHandGeometry> hands(const VasGeometry& geometry) {
    return {geometry.hands, geometry.hand_count};
}
inline View<VasMesh> segments(const VasHandGeometry& hand) {
    return {hand.segments, hand.segment_count};
}
inline View<float[3]> positions(const VasMesh& mesh) {
    return {mesh.positions, mesh.vertex_count};
}
/// The normals, one per position; empty when the server sent none.
inline View<float[3]> normals(const VasMesh& mesh) {
    return {mesh.normals, mesh.normals == nullptr ? 0 : mesh.vertex_count};
}
inline View<uint32_t[3]> triangles(const VasMesh& mesh) {
    return {mesh.triangles, mesh.triangle_count};
}
/// The segments of a hand frame that have a pose, in segment order (vas_hand_segment_name).
inline View<VasWirePose> segment_poses(const VasHandFrame& hand) {
    std::size_t count = std::min<std::size_t>(hand.segment_count, std::size(hand.segments));
    return {hand.segments, count};
}

/// A pose of vas (right-handed, z up, metres) in Unity's frame (left-handed, y up, metres).
inline VasWirePose to_unity(const VasWirePose& pose) {
    VasWirePose converted;
    check(vas_pose_to_unity(&pose, &converted), "convert a pose to Unity's frame");
    return converted;
}

/// A pose of vas in Unreal's frame (left-handed, z up, centimetres).
inline VasWirePose to_unreal(const VasWirePose& pose) {
    VasWirePose converted;
    check(vas_pose_to_unreal(&pose, &converted), "convert a pose to Unreal's frame");
    return converted;
}

/// A connection to a vas server, freed when it goes out of scope.
class Client {
public:
    /// Connects on `prefix` (the server's --prefix; null for the default) with `roles`
    /// (VAS_ROLE_* bits).
    static Client connect(const char* prefix, uint32_t roles = VAS_ROLE_RENDER,
                          bool handle_termination_signals = false) {
        VasClient* handle = nullptr;
        check(vas_client_connect(prefix, roles, handle_termination_signals, &handle),
              "connect to the vas server");
        return Client(handle);
    }

    Client(Client&& other) noexcept : handle_(std::exchange(other.handle_, nullptr)) {}
    Client& operator=(Client&& other) noexcept {
        if (this != &other) {
            vas_client_free(handle_);
            handle_ = std::exchange(other.handle_, nullptr);
        }
        return *this;
    }
    Client(const Client&) = delete;
    Client& operator=(const Client&) = delete;
    ~Client() { vas_client_free(handle_); }

    /// The handle, for the functions of vas_client.h this class does not wrap.
    VasClient* handle() const noexcept { return handle_; }

    /// Takes these roles as well (VAS_ROLE_* bits).
    void take_roles(uint32_t roles) { check(vas_client_take_roles(handle_, roles), "take roles"); }

    /// Blocks until output is ready to poll, `timeout` passes or a handled signal arrives.
    VasWake wait(std::chrono::milliseconds timeout) {
        VasWake wake = VAS_WAKE_TIMEOUT;
        check(vas_client_wait(handle_, millis(timeout), &wake), "wait for frames");
        return wake;
    }

    /// Receives every queued frame; ends the views of parts and hands handed out before.
    VasReceived poll() {
        VasReceived received{};
        check(vas_client_poll(handle_, &received), "poll");
        return received;
    }

    /// The newest scene geometry, or null before the first.
    const VasGeometry* geometry() {
        const VasGeometry* geometry = nullptr;
        return check(vas_client_geometry(handle_, &geometry), "read the geometry") ? geometry
                                                                                   : nullptr;
    }

    /// The newest parts frame, or none before the first.
    std::optional<PartsFrame> latest_parts() {
        VasPartsFrameHeader header{};
        const VasPartState* parts = nullptr;
        std::size_t count = 0;
        if (!check(vas_client_latest_parts(handle_, &header, &parts, &count),
                   "read the parts frame")) {
            return std::nullopt;
        }
        return PartsFrame{header, View<VasPartState>(parts, count)};
    }

    /// The newest frame of every hand, right hand first.
    View<VasHandFrame> latest_hands() {
        const VasHandFrame* hands = nullptr;
        std::size_t count = 0;
        check(vas_client_latest_hands(handle_, &hands, &count), "read the hand frames");
        return {hands, count};
    }

    /// A copy of the newest frame of user `user`'s hand on `side` (VAS_HAND_*), or none before
    /// the first.
    std::optional<VasHandFrame> latest_hand_of(uint32_t user, uint32_t side) {
        VasHandFrame hand{};
        if (!check(vas_client_latest_hand_of(handle_, user, side, &hand), "read a hand frame")) {
            return std::nullopt;
        }
        return hand;
    }

    /// A copy of the newest force frame, or none before the first.
    std::optional<VasForceFrame> latest_force() {
        VasForceFrame force{};
        if (!check(vas_client_latest_force(handle_, &force), "read the force frame")) {
            return std::nullopt;
        }
        return force;
    }

    /// The events received since the last take, oldest first; `dropped` (if not null) counts
    /// those lost meanwhile.
    View<VasSimEvent> take_events(uint64_t* dropped = nullptr) {
        const VasSimEvent* events = nullptr;
        std::size_t count = 0;
        check(vas_client_take_events(handle_, &events, &count, dropped), "take the events");
        return {events, count};
    }

    void send(const VasTrackerSample& sample) {
        check(vas_client_send_tracker(handle_, &sample), "send a tracker sample");
    }
    void send(const VasGloveSample& sample) {
        check(vas_client_send_glove(handle_, &sample), "send a glove sample");
    }
    void send(const VasHandJointsSample& sample) {
        check(vas_client_send_hand_joints(handle_, &sample), "send a hand-joints sample");
    }

    /// Returns once the server has taken in every sample sent before.
    void flush_inputs(std::chrono::milliseconds timeout) {
        check(vas_client_flush_inputs(handle_, millis(timeout)), "flush the inputs");
    }

    /// The server's scene, valid until the next scene_info or the client's end.
    const VasSceneInfo& scene_info(std::chrono::milliseconds timeout) {
        const VasSceneInfo* scene = nullptr;
        check(vas_client_scene_info(handle_, millis(timeout), &scene), "ask for the scene");
        return *scene;
    }

    void reset(std::chrono::milliseconds timeout) {
        check(vas_client_reset(handle_, millis(timeout)), "reset the scene");
    }
    void load_named_scene(const std::string& name, std::chrono::milliseconds timeout) {
        check(vas_client_load_named_scene(handle_, name.c_str(), millis(timeout)),
              "load a scene");
    }
    /// `metaphor` is a VAS_METAPHOR_* code.
    void set_metaphor(uint32_t metaphor, std::chrono::milliseconds timeout) {
        check(vas_client_set_metaphor(handle_, metaphor, millis(timeout)),
              "set the sliding metaphor");
    }

private:
    explicit Client(VasClient* handle) : handle_(handle) {}

    /// A time-out as the library takes it: whole milliseconds, none below zero.
    static uint64_t millis(std::chrono::milliseconds timeout) {
        return static_cast<uint64_t>(std::max<std::chrono::milliseconds::rep>(0, timeout.count()));
    }

    VasClient* handle_;
};

}  // namespace vas

#endif  // VAS_CLIENT_HPP
