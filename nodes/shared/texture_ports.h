// Enum ports shared by the texture nodes: the green-channel convention of tangent-space normal maps and the image
// wrap modes (typed enums with generated GLSL constants, core/graph/node_params.h).
#pragma once

#include "core/graph/node_params.h"

namespace specula::nodes {

enum class NormalMapConvention : int { OpenGL, DirectX };
enum class ImageWrap : int { Repeat, Clamp, Mirror };

}  // namespace specula::nodes

SPECULA_ENUM(specula::nodes::NormalMapConvention, "SPC_NORMAL_MAP", "opengl", "directx");
SPECULA_ENUM(specula::nodes::ImageWrap, "SPC_WRAP", "repeat", "clamp", "mirror");
