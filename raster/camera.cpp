// Orbit camera construction.
#include "raster/camera.h"

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <sstream>

#include "core/error.h"

namespace reliefsim {

Camera MakeOrbitCamera(float viewAngleDeg, float azimuthDeg, float distance,
                       float fovYDeg, float aspect) {
    auto fail = [](const char* subject, float value, const char* valid) {
        std::ostringstream s;
        s << "orbit camera " << subject << " " << value << ": out of range; expected "
          << valid;
        throw Error(s.str());
    };
    if (!(viewAngleDeg >= 0.0f && viewAngleDeg < 90.0f))
        fail("view angle", viewAngleDeg, "[0, 90) degrees");
    if (!std::isfinite(azimuthDeg))
        fail("azimuth", azimuthDeg, "a finite angle in degrees");
    if (!(distance > 0.0f && std::isfinite(distance))) fail("distance", distance, "> 0");
    if (!(fovYDeg > 0.0f && fovYDeg < 180.0f))
        fail("vertical fov", fovYDeg, "(0, 180) degrees");
    if (!(aspect > 0.0f && std::isfinite(aspect))) fail("aspect", aspect, "> 0");

    // Trigonometry in double, rounded once to float, so the camera does not depend on
    // libm's float variants.
    const double kPi = 3.14159265358979323846;
    const double theta = double(viewAngleDeg) * kPi / 180.0;
    const double phi = double(azimuthDeg) * kPi / 180.0;
    const double st = std::sin(theta), ct = std::cos(theta);
    const double sp = std::sin(phi), cp = std::cos(phi);
    const double d = double(distance);

    Camera cam;
    cam.eye = glm::vec3(float(d * st * sp), float(-d * st * cp), float(d * ct));
    // Horizontal direction from the camera toward the target is (-sp, cp, 0); up tilts it
    // by theta.
    const glm::vec3 up(float(-ct * sp), float(ct * cp), float(st));
    cam.viewFromWorld = glm::lookAtRH(cam.eye, glm::vec3(0.0f), up);
    cam.fovY = float(double(fovYDeg) * kPi / 180.0);
    cam.aspect = aspect;
    cam.nearZ = distance / 100.0f;
    cam.farZ = distance * 100.0f;
    cam.clipFromView = glm::perspectiveRH_NO(cam.fovY, aspect, cam.nearZ, cam.farZ);
    cam.clipFromWorld = cam.clipFromView * cam.viewFromWorld;
    return cam;
}

Camera MakeTileOrthoCamera() {
    Camera cam;
    cam.eye = glm::vec3(0.0f, 0.0f, 1.0f);
    cam.viewFromWorld =
        glm::lookAtRH(cam.eye, glm::vec3(0.0f), glm::vec3(0.0f, 1.0f, 0.0f));
    cam.aspect = 1.0f;
    cam.nearZ = 0.5f;
    cam.farZ = 1.5f;
    cam.clipFromView = glm::orthoRH_NO(-0.5f, 0.5f, -0.5f, 0.5f, cam.nearZ, cam.farZ);
    cam.clipFromWorld = cam.clipFromView * cam.viewFromWorld;
    return cam;
}

}  // namespace reliefsim
