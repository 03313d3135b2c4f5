// FCL 0.7's mesh-mesh distance with OBBRSS trees, the second peer of vas-bench distance (B11):
// reads the two meshes and B's poses the benchmark wrote, builds fcl::BVHModel<fcl::OBBRSSd> over
// each, and answers fcl::distance at every pose (A at the identity, so FCL's world frame is A's),
// timed as distance_harness.h says.
//
//   fcl-distance INPUT
#include <memory>

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/math/bv/OBBRSS.h>
#include <fcl/narrowphase/distance.h>

#include "distance_harness.h"

namespace {

std::shared_ptr<fcl::BVHModel<fcl::OBBRSSd>> build(const harness::Mesh& mesh) {
    std::vector<fcl::Vector3d> vertices;
    for (std::size_t i = 0; i < mesh.xyz.size(); i += 3) {
        vertices.emplace_back(mesh.xyz[i], mesh.xyz[i + 1], mesh.xyz[i + 2]);
    }
    std::vector<fcl::Triangle> triangles;
    for (std::size_t i = 0; i < mesh.abc.size(); i += 3) {
        triangles.emplace_back(mesh.abc[i], mesh.abc[i + 1], mesh.abc[i + 2]);
    }
    auto model = std::make_shared<fcl::BVHModel<fcl::OBBRSSd>>();
    model->beginModel();
    model->addSubModel(vertices, triangles);
    model->endModel();
    return model;
}

fcl::Transform3d transform(const harness::Pose& pose) {
    fcl::Matrix3d rotation;
    rotation << pose.rotation[0], pose.rotation[1], pose.rotation[2], pose.rotation[3],
        pose.rotation[4], pose.rotation[5], pose.rotation[6], pose.rotation[7],
        pose.rotation[8];
    fcl::Transform3d transform = fcl::Transform3d::Identity();
    transform.linear() = rotation;
    transform.translation() =
        fcl::Vector3d(pose.translation[0], pose.translation[1], pose.translation[2]);
    return transform;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: fcl-distance INPUT\n");
        return 2;
    }
    harness::Input input;
    if (!harness::read_input(argv[1], input)) {
        return 1;
    }
    const auto a = build(input.a);
    const auto b = build(input.b);
    std::vector<fcl::Transform3d> transforms;
    for (const harness::Pose& pose : input.poses) {
        transforms.push_back(transform(pose));
    }
    const fcl::Transform3d identity = fcl::Transform3d::Identity();
    fcl::DistanceRequestd request;
    request.enable_nearest_points = true;
    request.rel_err = 0.0;
    request.abs_err = 0.0;
    // The poses are converted before the timing, so the query is timed alone.
    const harness::Pose* first = input.poses.data();
    harness::run(input.poses, [&](const harness::Pose& pose) {
        fcl::DistanceResultd result;
        fcl::distance(a.get(), identity, b.get(), transforms[&pose - first], request, result);
        const fcl::Vector3d& p1 = result.nearest_points[0];
        const fcl::Vector3d& p2 = result.nearest_points[1];
        return harness::Answer{result.min_distance, {p1[0], p1[1], p1[2]}, {p2[0], p2[1], p2[2]},
                               static_cast<long long>(result.b1),
                               static_cast<long long>(result.b2)};
    });
    return 0;
}
