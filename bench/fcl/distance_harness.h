// What the distance harnesses of vas-bench distance (B11) share: reading the meshes and poses the
// benchmark writes, timing one query per pose as the benchmark times the DOP-tree's, and printing
// the answers. Each harness (coal's, FCL's) supplies only its build and its query.
//
// INPUT, little-endian: mesh A, mesh B, then u64 pose count and per pose 12 f64: B's rotation in
// A's frame (row-major 3x3), then its translation. A mesh: u64 vertex count, u64 triangle count,
// f64 x y z per vertex, u32 a b c per triangle.
//
// Output, one line per pose: distance, the nearest point on A and the one on B (both in A's
// frame), the triangles they lie on, and the query's time in nanoseconds.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <vector>

namespace harness {

struct Mesh {
    std::vector<double> xyz;
    std::vector<std::uint32_t> abc;
};

struct Pose {
    double rotation[9];
    double translation[3];
};

struct Answer {
    double distance;
    double on_a[3];
    double on_b[3];
    long long triangle_a;
    long long triangle_b;
};

struct Input {
    Mesh a;
    Mesh b;
    std::vector<Pose> poses;
};

inline bool read_mesh(std::ifstream& in, Mesh& mesh) {
    std::uint64_t counts[2];
    if (!in.read(reinterpret_cast<char*>(counts), sizeof counts)) {
        return false;
    }
    mesh.xyz.resize(counts[0] * 3);
    mesh.abc.resize(counts[1] * 3);
    in.read(reinterpret_cast<char*>(mesh.xyz.data()), mesh.xyz.size() * sizeof(double));
    in.read(reinterpret_cast<char*>(mesh.abc.data()), mesh.abc.size() * sizeof(std::uint32_t));
    return static_cast<bool>(in);
}

// Reads INPUT; false (with a message) when it is shorter than its counts say.
inline bool read_input(const char* path, Input& input) {
    std::ifstream in(path, std::ios::binary);
    std::uint64_t count = 0;
    if (!read_mesh(in, input.a) || !read_mesh(in, input.b) ||
        !in.read(reinterpret_cast<char*>(&count), sizeof count)) {
        std::fprintf(stderr, "cannot read the meshes of %s\n", path);
        return false;
    }
    input.poses.resize(count);
    in.read(reinterpret_cast<char*>(input.poses.data()), count * sizeof(Pose));
    if (!in) {
        std::fprintf(stderr, "%s is shorter than its pose count says\n", path);
        return false;
    }
    return true;
}

using Clock = std::chrono::steady_clock;

// The cost of reading the clock twice (median of many empty readings), subtracted from each
// query's time as the benchmark subtracts it from the DOP-tree's.
inline double timer_overhead_ns() {
    std::vector<double> samples(2001);
    for (double& sample : samples) {
        const auto start = Clock::now();
        sample = std::chrono::duration<double, std::nano>(Clock::now() - start).count();
    }
    std::nth_element(samples.begin(), samples.begin() + samples.size() / 2, samples.end());
    return samples[samples.size() / 2];
}

// One turn over the poses, as the benchmark runs the DOP-tree's: one untimed query at the last
// pose (on the tumbling path the one before the first), then each pose timed alone; prints each
// pose's answer and time.
template <class Query>
void run(const std::vector<Pose>& poses, Query query) {
    if (poses.empty()) {
        return;
    }
    const double overhead = timer_overhead_ns();
    std::vector<Answer> answers(poses.size());
    std::vector<double> nanoseconds(poses.size());
    answers[0] = query(poses.back());
    for (std::size_t i = 0; i < poses.size(); ++i) {
        const auto start = Clock::now();
        answers[i] = query(poses[i]);
        const double took = std::chrono::duration<double, std::nano>(Clock::now() - start).count();
        nanoseconds[i] = std::max(0.0, took - overhead);
    }
    for (std::size_t i = 0; i < poses.size(); ++i) {
        const Answer& a = answers[i];
        std::printf("%.17g %.17g %.17g %.17g %.17g %.17g %.17g %lld %lld %.1f\n", a.distance,
                    a.on_a[0], a.on_a[1], a.on_a[2], a.on_b[0], a.on_b[1], a.on_b[2],
                    a.triangle_a, a.triangle_b, nanoseconds[i]);
    }
}

}  // namespace harness
