// Pinhole camera (OpenGL conventions) and the orbit camera used by the scenes.
#pragma once

#include <glm/glm.hpp>

namespace reliefsim {

/// Camera matrices in OpenGL conventions: right-handed view space looking down -z, clip
/// space with NDC depth in [-1,1]. clipFromWorld = clipFromView * viewFromWorld.
struct Camera {
    glm::vec3 eye;            // world position of the centre of projection
    glm::mat4 viewFromWorld;  // right-handed look-at
    glm::mat4 clipFromView;   // OpenGL-style perspective, depth to [-1,1] NDC
    glm::mat4 clipFromWorld;  // clipFromView * viewFromWorld
    float fovY = 0.0f;        // vertical field of view, radians
    float aspect = 1.0f;      // width / height
    float nearZ = 0.0f;       // near plane distance, world units
    float farZ = 0.0f;        // far plane distance, world units
};

/// Orbit camera looking at the origin.
/// viewAngleDeg: angle between the view direction and the plane normal +z, degrees, [0,
/// 90). azimuthDeg: rotation of the camera around +z, degrees; 0 puts the camera on the
/// -y side looking toward +y. distance: eye distance from the origin (> 0). fovYDeg:
/// vertical field of view in degrees, (0, 180). aspect = width / height (> 0). The up
/// vector is the unit vector orthogonal to the view direction in the vertical plane that
/// contains it, so it is well defined at viewAngle 0 too (then image up is the azimuth's
/// +y). Near/far planes are distance/100 and distance*100. Throws reliefsim::Error on bad
/// input.
Camera MakeOrbitCamera(float viewAngleDeg, float azimuthDeg, float distance,
                       float fovYDeg, float aspect);

/// Orthographic camera looking straight down (-z) at the plane's square [-0.5, 0.5]^2,
/// which fills the image exactly (image up = +y): the texture-space view, where pixel
/// (x, y) of a W x H image sees the plane point of uv ((x + 0.5)/W, (y + 0.5)/H).
Camera MakeTileOrthoCamera();

}  // namespace reliefsim
