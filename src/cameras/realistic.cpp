#include "cameras/camera.h"
#include "core/error.h"

namespace gradus {

std::unique_ptr<Camera> CreateRealisticCamera(const CameraDesc &desc, Point2i) {
    throw UnsupportedError(desc.loc, "Camera \"realistic\"");
}

}  // namespace gradus
