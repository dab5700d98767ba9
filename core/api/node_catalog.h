// The node catalogue as JSON (libspecula: `specula nodes --json`, specula::api::nodeCatalogJson).
#pragma once

#include "core/graph/node_spec.h"

#include <nlohmann/json.hpp>

#include <string>

namespace specula {

// Shortest decimal text that reads back as the same float ("0.04", not "0.0399999991"); locale-independent.
std::string shortestFloatText(float v);

// Every field of one NodeSpec (id, version, category, doc, inputs, outputs, flags, glsl, parity).
nlohmann::ordered_json nodeSpecJson(const graph::NodeSpec& s);

// {"nodes": [nodeSpecJson of every registered node, sorted by id]}.
nlohmann::ordered_json nodeCatalogJson();

}  // namespace specula
