// Pixel reconstruction filters with pbrt-v3's parameters and defaults
// (xwidth/ywidth are radii).
#pragma once
#include <memory>

#include "core/geometry.h"
#include "parser/scene_desc.h"

namespace gradus {

class Filter {
  public:
    explicit Filter(Vec2 radius) : radius(radius) {}
    virtual ~Filter() = default;
    // Filter value at offset p from the pixel centre (|p.x| <= radius.x ...).
    virtual Float evaluate(Point2 p) const = 0;
    const Vec2 radius;
};

std::unique_ptr<Filter> CreateFilter(const EntityDesc &desc);

}  // namespace gradus
