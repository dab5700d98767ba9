// `specula nodes`: the node registry as text, JSON or the Markdown reference page (docs/nodes.md).
// Everything per node comes from its NodeSpec (notes included) and every category's notes from its folder
// (NodeRegistry::categoryNotes); the only fixed text here is the page's prose (conventions, parity measurements).
// Output is deterministic (sorted ids, locale-independent number formatting), so the committed page can be
// compared byte for byte with a fresh run (tests/unit/test_nodes_doc.cpp).
#include "plugin/cli/nodes_command.h"

#include "core/api/node_catalog.h"
#include "core/codegen/glsl_signature.h"
#include "core/graph/node_spec.h"
#include "core/io/image_io.h"
#include "core/util/error.h"
#include "plugin/cli/cli_output.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace specula {
namespace {

using namespace specula::graph;
using ojson = nlohmann::ordered_json;

const char* const kRegenerate = "build/bin/specula nodes --markdown -o docs/nodes.md";

// ---- formatting helpers ---------------------------------------------------------------------------

// Shortest decimal text that reads back as the same float ("0.04", not "0.0399999991"): libspecula's.
std::string num(float v) { return shortestFloatText(v); }

// A tolerance as written in prose: "1e-4", "2e-4", "0.12" (shortest round-trip digits).
std::string tolText(float v) {
    if (!(std::fabs(v) < 0.01f) || v == 0.f) return num(v);
    char buf[40];
    for (int prec = 0; prec <= 8; ++prec) {
        std::snprintf(buf, sizeof buf, "%.*e", prec, double(v));
        if (std::strtof(buf, nullptr) == v) break;
    }
    std::string t = buf;  // "2e-04"
    size_t e = t.find('e');
    std::string mant = t.substr(0, e), ex = t.substr(e + 1);
    bool neg = ex[0] == '-';
    ex = ex.substr(1);
    while (ex.size() > 1 && ex[0] == '0') ex.erase(0, 1);
    return mant + "e" + (neg ? "-" : "") + ex;
}

std::string vecText(const PortSpec& p) {
    int w = typeWidth(p.type);
    if (w == 1) return num(p.def[0]);
    std::string s = "(";
    for (int k = 0; k < w; ++k) s += (k ? ", " : "") + num(p.def[size_t(k)]);
    return s + ")";
}

bool hasMin(const PortSpec& p) { return std::isfinite(p.minValue); }
bool hasMax(const PortSpec& p) { return std::isfinite(p.maxValue); }

// Default of an input as plain text; "" when it has none (required, or read from a binding).
std::string defaultText(const PortSpec& p) {
    if (p.required) return "";
    if (p.binding != GeomBinding::None) return "";
    if (p.type == TypeDesc::String) return p.defString;
    if (!isNumeric(p.type)) return "";
    return vecText(p);
}

// The soft (usual) range, then the hard limits a literal must respect, where declared.
std::string rangeText(const PortSpec& p) {
    std::string r;
    if (hasMin(p) && hasMax(p)) r = "[" + num(p.minValue) + ", " + num(p.maxValue) + "]";
    else if (hasMin(p)) r = ">= " + num(p.minValue);
    else if (hasMax(p)) r = "<= " + num(p.maxValue);
    if (std::isfinite(p.softMin) || std::isfinite(p.softMax))
        r += (r.empty() ? "" : "; ") + std::string("warns outside [") + num(p.softMin) + ", " + num(p.softMax) + "]";
    const bool lo = std::isfinite(p.hardMin), hi = std::isfinite(p.hardMax);
    if (lo || hi) {
        std::string h = lo && hi ? "[" + num(p.hardMin) + ", " + num(p.hardMax) + "]" : lo ? ">= " + num(p.hardMin) : "<= " + num(p.hardMax);
        r += (r.empty() ? "" : "; ") + std::string("valid ") + h;
    }
    return r;
}

std::string join(const std::vector<std::string>& v, const std::string& sep) {
    std::string s;
    for (size_t i = 0; i < v.size(); ++i) s += (i ? sep : "") + v[i];
    return s;
}

std::string yesNo(bool b) { return b ? "yes" : "no"; }

std::string flagsText(const NodeSpec& s) {
    return "pure: " + yesNo(s.has(kPure)) + ", needs derivatives: " + yesNo(s.has(kNeedsDerivatives)) +
           ", emissive: " + yesNo(s.has(kEmissive));
}

// One Markdown table row from already escaped cells ("| a | b |", empty cells as "| |").
std::string row(const std::vector<std::string>& cells) {
    std::string r = "|";
    for (auto& c : cells) r += c.empty() ? " |" : " " + c + " |";
    return r + "\n";
}

// Markdown table cell: pipes escaped, no line breaks.
std::string cell(const std::string& text) {
    std::string s;
    for (char c : text) {
        if (c == '|')
            s += "\\|";
        else if (c == '\n')
            s += ' ';
        else
            s += c;
    }
    return s;
}

std::string code(const std::string& text) { return text.empty() ? "" : "`" + text + "`"; }

// GitHub heading anchor of "### `<id>`": lower case, punctuation other than '-' and '_' dropped.
std::string anchor(const std::string& heading) {
    std::string a;
    for (char c : heading) {
        unsigned char u = static_cast<unsigned char>(c);
        if (std::isalnum(u) || c == '-' || c == '_')
            a += char(std::tolower(u));
        else if (c == ' ')
            a += '-';
    }
    return a;
}

// Left-aligned text columns separated by two spaces; the last column is not padded.
std::string textTable(const std::vector<std::vector<std::string>>& rows, const std::string& indent) {
    std::vector<size_t> width;
    for (auto& r : rows)
        for (size_t c = 0; c + 1 < r.size(); ++c) {
            if (width.size() <= c) width.resize(c + 1, 0);
            width[c] = std::max(width[c], r[c].size());
        }
    std::string out;
    for (auto& r : rows) {
        std::string line = indent;
        for (size_t c = 0; c < r.size(); ++c) {
            line += r[c];
            if (c + 1 < r.size()) line += std::string(width[c] - r[c].size() + 2, ' ');
        }
        while (!line.empty() && line.back() == ' ') line.pop_back();
        out += line + "\n";
    }
    return out;
}

// ---- fixed prose of the reference page ------------------------------------------------------------

// Category order of the page (the families of node_spec.h); categories not listed follow alphabetically.
const std::vector<std::string>& categoryOrder() {
    static const std::vector<std::string> order = {"constant", "geometry", "texture", "math",
                                                   "convert",  "fresnel",  "bsdf",    "closure"};
    return order;
}

// ---- paste-able example materials -----------------------------------------------------------------
// Every node's section ends with a complete material ({"nodes": {...}, "output": "@x.bsdf"}) built from the
// registry: the node with every input a user can set (ports without a geometric binding) at its default, required
// closure inputs fed by default BSDFs, and a non-closure output wired into a BSDF input of its type. The only
// fixed data are below: the repository file a file port names, a few feeders (a normal map for texture.normal_map,
// LEAN moments for bsdf.beckmann_lean) and the BSDF each output type goes to. tests/docs/test_doc_examples.py loads
// every example, so a renamed port or node breaks the test, not a reader's paste.

// A file input of an example: a normal map in this repository (256x256), and a 128x128 one for bsdf.ltc_normal_map,
// which fits its prefiltered LTCs on load (about four times longer per doubling of the size: seconds at 128x128).
const char* const kExampleNormalMap = "examples/lean/bumps.png";
const char* const kExampleSmallNormalMap = "examples/showcase/stone128.png";

std::string exampleFile(const NodeSpec& s) {
    return s.id == "bsdf.ltc_normal_map" ? kExampleSmallNormalMap : kExampleNormalMap;
}

// One step of a chain from a node's output into a BSDF: node type, the input the previous value enters ("": the
// step's first input of that type), fixed literal inputs (JSON text), and further inputs taken from other outputs of
// the featured node.
struct ExampleStep {
    std::string type, input;
    std::vector<std::pair<std::string, std::string>> literals;
    std::vector<std::pair<std::string, std::string>> fromFeatured;  // (input, output of the featured node)
};

// Where a non-closure output goes, by type: a BSDF input of that type (through a converter where no BSDF has one).
std::vector<ExampleStep> sinkForType(TypeDesc t) {
    switch (t) {
        case TypeDesc::Color3: return {{"bsdf.diffuse", "color", {}, {}}};
        case TypeDesc::Float: return {{"bsdf.ggx", "roughness", {}, {}}};
        case TypeDesc::Normal3: return {{"bsdf.ggx", "normal", {}, {}}};
        case TypeDesc::Vector3: return {{"convert.vector3_to_color3", "", {}, {}}, {"bsdf.diffuse", "color", {}, {}}};
        case TypeDesc::Vec2: return {{"math.length.vec2", "", {}, {}}, {"bsdf.ggx", "roughness", {}, {}}};
        default: return {};
    }
}

// Nodes whose output has a more telling destination than the by-type default.
std::vector<ExampleStep> sinkFor(const NodeSpec& s, TypeDesc t) {
    if (s.category == "fresnel") {  // a Fresnel term weights a specular lobe whose own Fresnel is off
        ExampleStep ggx{"bsdf.ggx", "weight", {{"fresnel", "\"none\""}}, {}};
        if (t == TypeDesc::Float) return {{"convert.float_to_color3", "", {}, {}}, ggx};
        return {ggx};
    }
    if (s.id == "texture.image")  // the repository's images are normal maps
        return {{"texture.normal_map", "color", {}, {}}, {"bsdf.ggx", "normal", {}, {}}};
    if (s.id == "texture.lean")
        return {{"bsdf.beckmann_lean", "slope", {}, {{"covariance", "covariance"}}}};
    return sinkForType(t);
}

// Inputs of the featured node fed by another node: (featured id, input) -> (node type, its output, its inputs).
struct ExampleFeed {
    std::string type, output;
    std::vector<std::pair<std::string, std::string>> literals;
};
const std::map<std::pair<std::string, std::string>, ExampleFeed>& exampleFeeds() {
    static const std::string map = std::string("\"") + kExampleNormalMap + "\"";
    static const std::map<std::pair<std::string, std::string>, ExampleFeed> feeds = {
        {{"texture.normal_map", "color"}, {"texture.image", "color", {{"file", map}, {"colorspace", "\"raw\""}}}},
        {{"texture.normal_map", "dcolor_du"}, {"texture.image", "dcolor_du", {{"file", map}, {"colorspace", "\"raw\""}}}},
        {{"texture.normal_map", "dcolor_dv"}, {"texture.image", "dcolor_dv", {{"file", map}, {"colorspace", "\"raw\""}}}},
        {{"bsdf.beckmann_lean", "slope"}, {"texture.lean", "slope", {{"file", map}}}},
        {{"bsdf.beckmann_lean", "covariance"}, {"texture.lean", "covariance", {{"file", map}}}},
    };
    return feeds;
}

// JSON text of a port's default literal: a number, an array of the port's width, or a string.
std::string defaultJson(const PortSpec& p) {
    if (p.type == TypeDesc::String) return ojson(p.defString).dump();
    int w = typeWidth(p.type);
    if (w == 1) return num(p.def[0]);
    std::string s = "[";
    for (int k = 0; k < w; ++k) s += (k ? ", " : "") + num(p.def[size_t(k)]);
    return s + "]";
}

struct ExampleNode {
    std::string key, type;
    std::vector<std::pair<std::string, std::string>> inputs;  // port -> JSON text
};

struct ExampleGraph {
    std::vector<ExampleNode> nodes;
    std::set<std::string> keys;
    // A short node key from the type ("bsdf.ggx" -> "ggx", "math.add.float" -> "add"), unique in the graph.
    size_t add(const std::string& type) {
        size_t a = type.find('.');
        std::string base = a == std::string::npos ? type : type.substr(a + 1);
        size_t b = base.find('.');
        if (b != std::string::npos) base = base.substr(0, b);
        std::string key = base;
        for (int k = 2; keys.count(key); ++k) key = base + std::to_string(k);
        keys.insert(key);
        nodes.push_back({key, type, {}});
        return nodes.size() - 1;
    }
    // Input `port` of node i; replaces a value set before (a feeder overrides a default).
    void set(size_t i, const std::string& port, const std::string& value) {
        for (auto& in : nodes[i].inputs)
            if (in.first == port) {
                in.second = value;
                return;
            }
        nodes[i].inputs.push_back({port, value});
    }
};

[[noreturn]] void exampleError(const NodeSpec& s, const std::string& what) {
    throw std::logic_error("docs example of " + s.id + ": " + what + " (plugin/cli/nodes_command.cpp)");
}

const PortSpec* findInput(const NodeSpec& s, const std::string& name) {
    for (auto& p : s.inputs)
        if (p.name == name) return &p;
    return nullptr;
}

const NodeSpec& requireSpec(const NodeSpec& featured, const std::string& id) {
    const NodeSpec* s = NodeRegistry::instance().find(id);
    if (!s) exampleError(featured, "no node " + id);
    return *s;
}

// The example material of one node as pretty JSON text (one line per node; long input lists wrap).
std::string exampleMaterial(const NodeSpec& s) {
    ExampleGraph g;
    size_t self = g.add(s.id);
    const std::string selfKey = g.nodes[self].key;
    int closures = 0;
    std::vector<std::pair<std::string, std::string>> closureInputs;
    for (auto& p : s.inputs) {
        auto feed = exampleFeeds().find({s.id, p.name});
        if (feed != exampleFeeds().end()) {
            const NodeSpec& fs = requireSpec(s, feed->second.type);
            size_t f = SIZE_MAX;  // one feeder node per type serves several inputs (texture.lean slope + covariance)
            for (size_t i = 0; i < g.nodes.size(); ++i)
                if (g.nodes[i].type == fs.id) f = i;
            if (f == SIZE_MAX) {
                f = g.add(fs.id);
                for (auto& l : feed->second.literals) g.set(f, l.first, l.second);
            }
            g.set(self, p.name, "\"@" + g.nodes[f].key + "." + feed->second.output + "\"");
            continue;
        }
        if (p.type == TypeDesc::Closure) {
            // Closure inputs: a diffuse base first, then a glossy one (closure.add/mix: diffuse + ggx).
            const char* type = closures++ == 0 ? "bsdf.diffuse" : "bsdf.ggx";
            size_t c = g.add(type);
            g.set(self, p.name, "\"@" + g.nodes[c].key + ".bsdf\"");
            continue;
        }
        if (p.binding != GeomBinding::None) continue;  // geometry: leave unconnected
        if (p.type == TypeDesc::String && p.enumValues.empty() && p.defString.empty()) {
            // required plain strings: a colorspace, or a file
            g.set(self, p.name, p.name == "colorspace" ? "\"raw\"" : ojson(exampleFile(s)).dump());
            continue;
        }
        g.set(self, p.name, defaultJson(p));
    }

    std::string output;
    const PortSpec* closureOut = nullptr;
    for (auto& o : s.outputs)
        if (o.type == TypeDesc::Closure) {
            closureOut = &o;
            break;
        }
    if (closureOut) {
        output = "@" + selfKey + "." + closureOut->name;
    } else {
        if (s.outputs.empty()) exampleError(s, "no output");
        // The first output, except where the chain below takes another one (texture.lean: its slope moments).
        const PortSpec* outp = &s.outputs.front();
        for (auto& o : s.outputs)
            if (s.id == "texture.lean" && o.name == "slope") outp = &o;
        const PortSpec& out = *outp;
        std::vector<ExampleStep> chain = sinkFor(s, out.type);
        if (chain.empty()) exampleError(s, std::string("no BSDF input for type ") + typeName(out.type));
        std::string ref = "@" + selfKey + "." + out.name;
        TypeDesc t = out.type;
        for (auto& step : chain) {
            const NodeSpec& ss = requireSpec(s, step.type);
            const PortSpec* in = nullptr;
            for (auto& p : ss.inputs)
                if (step.input.empty() ? p.type == t && p.binding == GeomBinding::None : p.name == step.input) {
                    in = &p;
                    break;
                }
            if (!in || in->type != t) exampleError(s, step.type + " has no " + typeName(t) + " input " + step.input);
            size_t k = g.add(ss.id);
            for (auto& l : step.literals) g.set(k, l.first, l.second);
            g.set(k, in->name, "\"" + ref + "\"");
            for (auto& f : step.fromFeatured) g.set(k, f.first, "\"@" + selfKey + "." + f.second + "\"");
            if (ss.outputs.empty()) exampleError(s, step.type + " has no output");
            ref = "@" + g.nodes[k].key + "." + ss.outputs.front().name;
            t = ss.outputs.front().type;
        }
        if (t != TypeDesc::Closure) exampleError(s, "the chain does not end in a closure");
        output = ref;
    }

    // Layout: "key": { "type": ..., "inputs": { ... } } on one line when it fits in 118 columns, else the inputs
    // wrap, several per line.
    const size_t kWidth = 118;
    size_t keyWidth = 0;
    for (auto& n : g.nodes) keyWidth = std::max(keyWidth, n.key.size());
    std::string text = "{\n  \"nodes\": {\n";
    for (size_t i = 0; i < g.nodes.size(); ++i) {
        const ExampleNode& n = g.nodes[i];
        std::string head = "    " + ojson(n.key).dump() + ":" + std::string(keyWidth - n.key.size() + 1, ' ') +
                           "{ \"type\": " + ojson(n.type).dump();
        std::vector<std::string> items;
        for (auto& in : n.inputs) items.push_back(ojson(in.first).dump() + ": " + in.second);
        std::string tail = i + 1 < g.nodes.size() ? " },\n" : " }\n";
        std::string line = head;
        if (!items.empty()) line += ", \"inputs\": { " + join(items, ", ") + " }";
        if (line.size() + tail.size() - 1 <= kWidth) {
            text += line + tail;
            continue;
        }
        text += head + ", \"inputs\": {\n";
        const std::string indent = "      ";
        std::string cur = indent;
        for (size_t k = 0; k < items.size(); ++k) {
            std::string item = items[k] + (k + 1 < items.size() ? "," : "");
            if (cur.size() > indent.size() && cur.size() + 1 + item.size() > kWidth) {
                text += cur + "\n";
                cur = indent;
            }
            cur += (cur.size() > indent.size() ? " " : "") + item;
        }
        text += cur + "\n    }" + tail;
    }
    text += "  },\n  \"output\": " + ojson(output).dump() + "\n}\n";
    return text;
}

std::string pageHeader(size_t nodeCount, size_t categoryCount) {
    std::string h;
    h += "# Node reference\n\n";
    h += "<!-- Generated by `specula nodes --markdown` (plugin/cli/nodes_command.cpp) from the node registry: do not "
         "edit.\n     Regenerate: ";
    h += kRegenerate;
    h += " -->\n\n";
    h += "This page is generated from the node registry: every node's `NodeSpec` (id, version, ports, defaults, "
         "ranges,\nbindings, flags, parity tolerance) is declared once, in C++, in its node file. Regenerate it with\n`";
    h += kRegenerate;
    h += "`; `tests/unit/test_nodes_doc.cpp` fails when it is out of date.\n"
         "`specula nodes` lists the registry, `specula nodes ID` prints one node and `specula nodes --json` the\n"
         "machine-readable form of every field.\n\n";
    h += "A material graph names a node by its id in `\"type\"` and sets inputs by port name, to a literal or to a "
         "reference\n`\"@node.output\"`; an unlisted input takes its default, or its geometric binding. See\n"
         "[graph-format.md](graph-format.md) for the graph syntax, the type rules, bindings and errors.\n\n";
    h += std::to_string(nodeCount) + " nodes in " + std::to_string(categoryCount) + " categories.\n\n";

    h += "## Conventions\n\n";
    h += "Each node is a folder `nodes/<family>/<node>/` with `<node>.node.cpp` (a parameter struct and one `NodeParams` "
         "list\nbinding each member to its port, the CPU entry, registration via `SPECULA_REGISTER_NODES`) and "
         "`<node>.glsl`\n(embedded into the binary at build time). Typed families register several specs from one "
         "folder (`math.add.float`,\n`math.add.vec2`, ...), sharing one `.glsl` with overloads. The GLSL function is "
         "bound to the ports by parameter\nname (`SpeculaClosureQuery q` first for BSDFs, `SpeculaShadingInputs s`, "
         "inputs, outputs, resources; enum ports\nare `int` constants `SPC_<ENUM>_<VALUE>`, plain string ports stay on "
         "the host); the prototypes below are the bound ones\n(docs/graph-format.md).\n\n";
    h += "Input tables:\n\n"
         "- **default**: the value of an unlisted input (a number fills every component). Empty when the input is "
         "required\n  (closures, file names, colorspaces) or reads a binding.\n"
         "- **range**: the documented soft range (not enforced; the parity suite samples inside it), or for an enum "
         "port\n  its values (GLSL gets the index; the first is the default).\n"
         "- **binding**: the default geometric binding of an unconnected input (`uv0`, `duv0dx`, `duv0dy`, `P`, `N`, "
         "`Ng`,\n  `T`, `Tsign`, `NdotV`; see [graph-format.md](graph-format.md#rules)), read by both backends.\n\n"
         "Flags: **pure** nodes are constant-folded when all their inputs are constant; **needs derivatives** nodes "
         "read\nscreen-space differentials (CPU ray differentials, GLSL `dFdx/dFdy`); **emissive** nodes can produce "
         "emission.\n\n";

    h += "## Examples\n\n";
    h += "Every node's section ends with a complete material that uses it, generated from the registry like the rest of "
         "the\npage: paste it as the value of an entry of a scene's `\"materials\"` object, or save it as "
         "`{\"materials\": {\"m\": ...}}` for\n`specula bsdf`, `specula glsl` and `specula plot`. Every input "
         "without a geometric binding is listed at its default,\nso an example also spells each port; closure inputs "
         "are fed by `bsdf.diffuse` and `bsdf.ggx`, and a node without a\nclosure output feeds a BSDF input of its "
         "output's type (through a `convert.*` or `math.*` node where no BSDF has\none). File inputs name normal maps in this repository: `";
    h += kExampleNormalMap;
    h += "`, and for\n`bsdf.ltc_normal_map`, which prefilters its map on load, the smaller `";
    h += kExampleSmallNormalMap;
    h += "`. File paths are\nrelative to the scene file, so as written the examples load from a file in the "
         "repository's root; elsewhere, change\nthe path. "
         "`tests/docs/test_doc_examples.py` (ctest `doc_examples`) loads every example of the documentation.\n\n";
    h += "## CPU/GLSL parity\n\n";
    h += "ctest label `glsl`, `tests/glsl/test_glsl_parity.cpp`: per node, 1024 random input sets (inside each port's\n"
         "documented range; uniform ports at their default, as one material has one value; normals/tangents random\n"
         "unit vectors; directions 85 % above the BSDF's normal) run through the node's GLSL on Mesa llvmpipe "
         "(headless\nEGL, RGBA32F) and through the CPU program; error metric\n"
         "`|gpu − cpu| / max(|cpu|, 1e-3)`. The tolerance is `NodeSpec::parityTolerance` (default 1e-4; a looser one "
         "carries\na `parityNote`), listed under each node below, so the test and this page use one number.\n\n";
    h += "Measured maximum relative errors (Mesa 22.3.6 / LLVM 15, llvmpipe; measurements, not registry data; nodes "
         "added\nlater quote theirs in their parity note):\n\n"
         "| node(s) | measured max rel. error | note |\n"
         "|---|---|---|\n"
         "| constant.\\*, convert.\\*, geometry.\\*, math.add/sub/mul/div/mix/clamp/remap/dot/normalize/length.\\* | 0 "
         "(bit-exact) | |\n"
         "| math.pow.\\* | 6.8e-7 | llvmpipe `pow` = exp2·log2 |\n"
         "| fresnel.schlick / dielectric / conductor | 1.7e-7 / 0 / 8.1e-7 | |\n"
         "| bsdf.diffuse | 4.2e-6 | |\n"
         "| bsdf.ggx | 5.1e-6 | roughness sampled in [0.1, 1] (α ≥ 0.01); below, D's conditioning (∝ 1/α) dominates "
         "float error in both backends |\n"
         "| bsdf.emission | 0 | |\n"
         "| closure.add / closure.mix | 1.9e-6 / 3.0e-6 | closure inputs are bsdf.diffuse on both sides |\n"
         "| closure.coat | 1.7e-5 | base = bsdf.diffuse; roughness over [0, 1] (α down to 1e-4: the GLSL repeats ggx::ndf's "
         "operation order); the albedo table interpolated with texelFetch on both sides |\n"
         "| texture.normal_map | 9.0e-5 | frame build + renormalisation (sqrt/divide, FMA contraction in llvmpipe) |\n"
         "| texture.image | 8.4e-5 | zero footprint (bilinear, level 0), wrap repeat, uv ∈ [−1, 2]; OIIO vs llvmpipe "
         "bilinear weight rounding. Non-zero footprints are *not* compared: OIIO's anisotropic filter and GL trilinear "
         "differ by design |\n"
         "| emitted modules (tests/glsl/data/materials.json: gold_mirror, brushed_steel, plastic, bumpy_copper) | ≤ "
         "1.4e-5 | whole module: uniform block, bindings, specula_eval/emission; tolerance 2e-4 |\n\n";
    h += "Polygon queries (LTC quad lights, `tests/glsl/test_glsl_ltc.cpp`): bsdf.diffuse, bsdf.ggx, bsdf.ggx_filtered "
         "and\nbsdf.beckmann_lean answer `SPC_QUERY_POLYGON` through `nodes/shared/ltc.glsl` with the LTC tables bound "
         "as\nbuilt-in resources. 4096 random frames, parameters, views and quads (fully above the horizon, straddling "
         "it,\nseen from behind) per node, both horizon modes, against `Closure::integratePolygon`; same error metric. "
         "Measured\nmaxima (clip / clip-free): diffuse 1.8e-5 / 1.9e-5, ggx 6.4e-5 / 4.0e-5, ggx_filtered 2.5e-5 / "
         "2.5e-5,\nbeckmann_lean 3.2e-5 / 2.6e-5 (tolerance 1e-4); an emitted closure.mix of diffuse and anisotropic "
         "ggx bound\nfrom its manifest: 1.2e-5; closure.coat over that mix: 9.2e-6.\n\n";
    return h;
}

// ---- registry views ------------------------------------------------------------------------------

std::vector<std::string> orderedCategories(const std::vector<const NodeSpec*>& all) {
    std::set<std::string> present;
    for (auto* s : all) present.insert(s->category);
    std::vector<std::string> out;
    for (auto& c : categoryOrder())
        if (present.erase(c)) out.push_back(c);
    out.insert(out.end(), present.begin(), present.end());  // std::set: sorted
    return out;
}

std::string nodeMarkdown(const NodeSpec& s) {
    std::string m = "### `" + s.id + "`\n\n";
    m += s.doc + "\n\n";
    if (!s.notes.empty()) m += "Notes: " + s.notes + "\n\n";
    m += "- version " + std::to_string(s.version) + ", category `" + s.category + "`\n";
    m += "- flags: " + flagsText(s) + "\n";
    m += "- GLSL: `" + s.glslPrototype() + "`";
    if (!s.glslFile.empty()) m += " in `nodes/" + s.glslFile + "`";
    m += "\n";
    if (!s.glslLibraries.empty()) {
        std::vector<std::string> libs;
        for (auto& l : s.glslLibraries) libs.push_back("`nodes/" + l + "`");
        m += "- GLSL libraries: " + join(libs, ", ") + "\n";
    }
    if (!s.gpuSubstitute.empty())
        m += "- **GPU: not supported.** The GLSL function substitutes " + s.gpuSubstitute +
             " `specula glsl` warns once per module; the parity suite checks the substitute against its CPU twin.\n";
    m += "- parity tolerance: " + tolText(s.parityTolerance);
    if (!s.parityNote.empty()) m += " — " + s.parityNote;
    m += "\n\n";
    if (!s.resources.empty()) {
        m += "| resource | GLSL type | kind | doc |\n|---|---|---|---|\n";
        for (auto& r : s.resources)
            m += row({code(cell(r.name)), code(r.glslType), resourceKindName(r.kind), cell(r.doc)});
        m += "\n";
    }
    if (!s.inputs.empty()) {
        m += "| input | type | default | range | binding | doc |\n|---|---|---|---|---|---|\n";
        for (auto& p : s.inputs) {
            std::string def = p.required ? "*required*" : cell(code(defaultText(p)));
            std::string range;
            if (!p.enumValues.empty()) {
                std::vector<std::string> vals;
                for (auto& v : p.enumValues) vals.push_back(code(v));
                range = cell(join(vals, " | "));
            } else {
                range = cell(rangeText(p));
            }
            m += row({code(cell(p.name)), typeName(p.type), def, range, cell(code(bindingName(p.binding))), cell(p.doc)});
        }
        m += "\n";
    }
    if (!s.outputs.empty()) {
        m += "| output | type | doc |\n|---|---|---|\n";
        for (auto& p : s.outputs) m += row({code(cell(p.name)), typeName(p.type), cell(p.doc)});
        m += "\n";
    }
    const std::string example = exampleMaterial(s);
    m += example.find("\"examples/") != std::string::npos
             ? "Example (a complete material; the file path is relative to the repository root, see [Examples](#examples)):"
             : "Example (a complete material, see [Examples](#examples)):";
    m += "\n\n```json\n" + example + "```\n\n";
    return m;
}

std::string registryMarkdown(const std::vector<const NodeSpec*>& all) {
    std::vector<std::string> cats = orderedCategories(all);
    std::string m = pageHeader(all.size(), cats.size());
    m += "## Contents\n\n";
    for (auto& c : cats) {
        std::vector<std::string> links;
        for (auto* s : all)
            if (s->category == c) links.push_back("[`" + s->id + "`](#" + anchor(s->id) + ")");
        m += "- [" + c + "](#" + anchor(c) + "): " + join(links, ", ") + "\n";
    }
    m += "\n";
    for (auto& c : cats) {
        m += "## " + c + "\n\n";
        const std::string& notes = NodeRegistry::instance().categoryNotes(c);  // nodes/<category>/category.cpp
        if (!notes.empty()) m += notes + "\n\n";
        for (auto* s : all)
            if (s->category == c) m += nodeMarkdown(*s);
    }
    while (m.size() >= 2 && m[m.size() - 1] == '\n' && m[m.size() - 2] == '\n') m.pop_back();
    return m;
}

std::string listingText(const std::vector<const NodeSpec*>& all) {
    std::vector<std::vector<std::string>> rows;
    for (auto* s : all) rows.push_back({s->id, s->category, s->doc});
    return textTable(rows, "");
}

std::string nodeText(const NodeSpec& s) {
    std::string t = s.id + "  (version " + std::to_string(s.version) + ", category " + s.category + ")\n";
    t += "  " + s.doc + "\n";
    if (!s.notes.empty()) t += "  Notes: " + s.notes + "\n";
    t += "inputs:\n";
    std::vector<std::vector<std::string>> rows;
    for (auto& p : s.inputs) {
        std::string def;
        if (p.required)
            def = "required";
        else if (p.binding != GeomBinding::None)
            def = std::string("binding ") + bindingName(p.binding);
        else
            def = "default " + (p.type == TypeDesc::String ? p.defString : vecText(p));
        std::string range = !p.enumValues.empty() ? "values " + join(p.enumValues, "|")
                                                  : (rangeText(p).empty() ? "" : "range " + rangeText(p));
        rows.push_back({p.name, typeName(p.type), def, range, p.doc});
    }
    t += rows.empty() ? "  (none)\n" : textTable(rows, "  ");
    t += "outputs:\n";
    rows.clear();
    for (auto& p : s.outputs) rows.push_back({p.name, typeName(p.type), p.doc});
    t += rows.empty() ? "  (none)\n" : textTable(rows, "  ");
    t += "flags: " + flagsText(s) + "\n";
    t += "glsl: " + s.glslPrototype() + (s.glslFile.empty() ? "" : "  (nodes/" + s.glslFile + ")") + "\n";
    if (!s.gpuSubstitute.empty()) t += "gpu: not supported; the GLSL substitutes " + s.gpuSubstitute + "\n";
    t += "parity tolerance: " + tolText(s.parityTolerance) + (s.parityNote.empty() ? "" : " — " + s.parityNote) + "\n";
    return t;
}

// Suggestion for an unknown id: the nearest registered id, or the first typed variant of a family name.
std::string suggestId(const std::string& id, const std::vector<std::string>& ids) {
    std::string best = nearestName(id, ids);
    if (!best.empty()) return best;
    for (auto& c : ids)
        if (c.rfind(id + ".", 0) == 0) return c;
    return "";
}

}  // namespace

void addNodesCommand(CLI::App& app, int& exitCode) {
    struct Opts {
        std::string id, out;
        bool json = false, markdown = false;
    };
    auto o = std::make_shared<Opts>();
    auto* cmd = app.add_subcommand("nodes", "List the registered shading nodes, print one node's spec, or write the "
                                            "registry as JSON or as the Markdown node reference (docs/nodes.md)");
    cmd->add_option("id", o->id, "Node id (e.g. bsdf.ggx): print only this node");
    auto* json = cmd->add_flag("--json", o->json, "Machine-readable registry: every NodeSpec field");
    auto* md = cmd->add_flag("--markdown", o->markdown, "The Markdown node reference (" + std::string(kRegenerate) + ")");
    json->excludes(md);
    md->excludes(json);
    cmd->add_option("-o,--output", o->out, "Write to FILE (atomically) instead of stdout");
    cmd->callback([o, &exitCode] {
        const NodeRegistry& reg = NodeRegistry::instance();
        std::vector<const NodeSpec*> all = reg.all();
        const NodeSpec* one = nullptr;
        if (!o->id.empty()) {
            one = reg.find(o->id);
            if (!one) {
                std::string sug = suggestId(o->id, reg.ids());
                std::fprintf(stderr, "specula: error: unknown node '%s'%s; `specula nodes` lists all %zu nodes\n",
                             o->id.c_str(), sug.empty() ? "" : (" (did you mean '" + sug + "'?)").c_str(), all.size());
                exitCode = kExitBadInput;
                return;
            }
        }
        std::string text;
        if (o->json) {
            ojson j;
            if (one) {
                j = nodeSpecJson(*one);
            } else {
                j["nodes"] = ojson::array();
                for (auto* s : all) j["nodes"].push_back(nodeSpecJson(*s));
            }
            text = j.dump(2) + "\n";
        } else if (o->markdown) {
            text = one ? nodeMarkdown(*one) : registryMarkdown(all);
            while (text.size() >= 2 && text[text.size() - 1] == '\n' && text[text.size() - 2] == '\n') text.pop_back();
        } else {
            text = one ? nodeText(*one) : listingText(all);
        }
        if (o->out.empty()) {
            std::fwrite(text.data(), 1, text.size(), stdout);
            std::fflush(stdout);
            return;
        }
        if (!outputFolderExists(o->out)) {
            exitCode = kExitIo;
            return;
        }
        try {
            writeFileAtomic(o->out, text);
        } catch (const std::exception& e) {
            std::fprintf(stderr, "specula: error: %s\n", e.what());
            exitCode = kExitIo;
        }
    });
}

}  // namespace specula
