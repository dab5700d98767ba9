// Built-in shapes (sphere, quad, disk, cylinder, torus) tessellated in object space with analytic
// UVs/tangents, each paired with its AnalyticSurface for exact shading attributes at hits.
#pragma once

#include "core/geometry/mesh.h"

namespace specula {

// All built-ins are centred at the object-space origin with z as their axis (z-up, like Blender).
// Parameterisation (u,v in [0,1]):
//   sphere:   u = phi/(2pi) with phi = atan2(y,x) in [0,2pi), v = theta/pi with theta from +z (v=0 at north pole)
//   quad:     the square [-sx/2,sx/2]x[-sy/2,sy/2] in the z=0 plane, u = x/sx+1/2, v = y/sy+1/2, normal +z
//   disk:     radius r in z=0, u = phi/(2pi), v = 1 - rho/r, normal +z
//   cylinder: radius r, z in [0,h] (open tube), u = phi/(2pi), v = z/h, normal outward
//   torus:    major radius R around z, minor radius r, u = phi/(2pi), v = psi/(2pi), psi measured in the tube
// 'segments' controls tessellation density (around the main circle); rings are chosen proportionally.
BuiltinShape makeSphere(float radius, int segments = 128);
BuiltinShape makeQuad(float sizeX, float sizeY);
BuiltinShape makeDisk(float radius, int segments = 128);
BuiltinShape makeCylinder(float radius, float height, int segments = 128);
BuiltinShape makeTorus(float majorRadius, float minorRadius, int segments = 128);

}  // namespace specula
