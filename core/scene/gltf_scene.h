// glTF 2.0 files as scenes (`specula render model.gltf`, issue 17 item 2): the file's camera, KHR_lights_punctual
// lights and metallic-roughness materials become a scene document that the scene loader reads like any other.
#pragma once

#include <nlohmann/json.hpp>

#include <string>

namespace specula {

// True for a .gltf or .glb path (any case): loadScene imports it instead of reading JSON.
bool isGltfScenePath(const std::string& path);

// The scene document of a glTF file (docs/scene-format.md "glTF scenes"): glTF's y-up world turned z-up as Blender
// imports it (+90 degrees about x); one mesh shape per material; the first camera of the default scene, or a camera
// framing the bounds; lights in Blender's conversion (683 lm/W); a uniform environment. Images the materials use are
// written to the texture cache and named by content. Throws IoError (unreadable file) or InputError.
nlohmann::json gltfSceneDocument(const std::string& path);

}  // namespace specula
