// FCL's OBB-tree build, the peer of vas-bench tree-build: reads a mesh written by the benchmark,
// builds fcl::BVHModel<fcl::OBBd> over it RUNS times on one thread, and prints one JSON object
// with each build's seconds and the model's bytes: its nodes, primitive indices, triangles and
// vertices (FCL's memUsage counts these but returns a status, not the count).
//
//   obb_build MESH RUNS
//
// MESH: u64 vertex count, u64 triangle count, then f64 x y z per vertex, then u32 a b c per
// triangle, little-endian.
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <vector>

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/math/bv/OBB.h>

int main(int argc, char** argv) {
    if (argc != 3) {
        std::fprintf(stderr, "usage: obb_build MESH RUNS\n");
        return 2;
    }
    std::ifstream in(argv[1], std::ios::binary);
    std::uint64_t counts[2];
    if (!in.read(reinterpret_cast<char*>(counts), sizeof counts)) {
        std::fprintf(stderr, "cannot read %s\n", argv[1]);
        return 1;
    }
    std::vector<double> xyz(counts[0] * 3);
    std::vector<std::uint32_t> abc(counts[1] * 3);
    in.read(reinterpret_cast<char*>(xyz.data()), xyz.size() * sizeof(double));
    in.read(reinterpret_cast<char*>(abc.data()), abc.size() * sizeof(std::uint32_t));
    if (!in) {
        std::fprintf(stderr, "%s is shorter than its counts say\n", argv[1]);
        return 1;
    }
    std::vector<fcl::Vector3d> vertices;
    vertices.reserve(counts[0]);
    for (std::size_t i = 0; i < counts[0]; ++i) {
        vertices.emplace_back(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    }
    std::vector<fcl::Triangle> triangles;
    triangles.reserve(counts[1]);
    for (std::size_t i = 0; i < counts[1]; ++i) {
        triangles.emplace_back(abc[3 * i], abc[3 * i + 1], abc[3 * i + 2]);
    }
    const int runs = std::atoi(argv[2]);
    std::printf("{\"seconds\": [");
    std::size_t bytes = 0;
    for (int run = 0; run < runs; ++run) {
        fcl::BVHModel<fcl::OBBd> model;
        const auto start = std::chrono::steady_clock::now();
        model.beginModel();
        model.addSubModel(vertices, triangles);
        model.endModel();
        const std::chrono::duration<double> took = std::chrono::steady_clock::now() - start;
        std::printf("%s%.6f", run ? ", " : "", took.count());
        bytes = model.getNumBVs() * sizeof(fcl::BVNode<fcl::OBBd>) +
                model.num_tris * (sizeof(fcl::Triangle) + sizeof(unsigned int)) +
                model.num_vertices * sizeof(fcl::Vector3d);
    }
    std::printf("], \"bytes\": %zu}\n", bytes);
    return 0;
}
