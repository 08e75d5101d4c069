// The rays: camera rays (a pinhole camera looking at the scene), diffuse rays (cosine-weighted directions from the
// first hits of the camera rays, about the facing geometric normal) and shadow rays (from the same points to a
// point light above the scene, tMax the distance). Every engine gets the same VkasRay arrays.
#pragma once

#include "common.hpp"

namespace vb {

std::vector<VkasRay> cameraRays(const Scene& scene, size_t count);

// `camera` and `cameraHits` (the reference engine's closest hits of the camera rays) give the surface points;
// `count` rays cycle over them. Throws when no camera ray hit anything.
std::vector<VkasRay> secondaryRays(const Scene& scene, RayKind kind, const std::vector<VkasRay>& camera,
                                   const std::vector<Hit>& cameraHits, size_t count);

}  // namespace vb
