// coal 3.0.3's mesh-mesh distance with OBBRSS trees, the peer of vas-bench distance (B11): reads
// the two meshes and B's poses the benchmark wrote, builds coal::BVHModel<coal::OBBRSS> over each,
// and answers coal::distance at every pose (A at the identity, so coal's world frame is A's),
// timed as distance_harness.h says.
//
//   coal-distance INPUT
#include <memory>

#include <coal/BV/OBBRSS.h>
#include <coal/BVH/BVH_model.h>
#include <coal/distance.h>

#include "../fcl/distance_harness.h"

namespace {

std::shared_ptr<coal::BVHModel<coal::OBBRSS>> build(const harness::Mesh& mesh) {
    std::vector<coal::Vec3s> vertices;
    for (std::size_t i = 0; i < mesh.xyz.size(); i += 3) {
        vertices.emplace_back(mesh.xyz[i], mesh.xyz[i + 1], mesh.xyz[i + 2]);
    }
    std::vector<coal::Triangle> triangles;
    for (std::size_t i = 0; i < mesh.abc.size(); i += 3) {
        triangles.emplace_back(mesh.abc[i], mesh.abc[i + 1], mesh.abc[i + 2]);
    }
    auto model = std::make_shared<coal::BVHModel<coal::OBBRSS>>();
    model->beginModel();
    model->addSubModel(vertices, triangles);
    model->endModel();
    return model;
}

coal::Transform3s transform(const harness::Pose& pose) {
    coal::Matrix3s rotation;
    rotation << pose.rotation[0], pose.rotation[1], pose.rotation[2], pose.rotation[3],
        pose.rotation[4], pose.rotation[5], pose.rotation[6], pose.rotation[7],
        pose.rotation[8];
    return coal::Transform3s(
        rotation, coal::Vec3s(pose.translation[0], pose.translation[1], pose.translation[2]));
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: coal-distance INPUT\n");
        return 2;
    }
    harness::Input input;
    if (!harness::read_input(argv[1], input)) {
        return 1;
    }
    const auto a = build(input.a);
    const auto b = build(input.b);
    std::vector<coal::Transform3s> transforms;
    for (const harness::Pose& pose : input.poses) {
        transforms.push_back(transform(pose));
    }
    const coal::Transform3s identity;
    const coal::DistanceRequest request(true, true, 0.0, 0.0);
    // The poses are converted before the timing, so the query is timed alone.
    const harness::Pose* first = input.poses.data();
    harness::run(input.poses, [&](const harness::Pose& pose) {
        coal::DistanceResult result;
        coal::distance(a.get(), identity, b.get(), transforms[&pose - first], request, result);
        const coal::Vec3s& p1 = result.nearest_points[0];
        const coal::Vec3s& p2 = result.nearest_points[1];
        return harness::Answer{result.min_distance, {p1[0], p1[1], p1[2]}, {p2[0], p2[1], p2[2]},
                               result.b1, result.b2};
    });
    return 0;
}
