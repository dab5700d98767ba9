// NodeRegistry, NodeSpec helpers and the geometric default bindings.
#include "core/graph/node_spec.h"

#include "core/render/shading.h"

#include <mutex>
#include <cstdio>
#include <cstdlib>

namespace specula::graph {

const char* bindingName(GeomBinding b) {
    switch (b) {
        case GeomBinding::None: return "";
        case GeomBinding::UV: return "uv0";
        case GeomBinding::DUVDX: return "duv0dx";
        case GeomBinding::DUVDY: return "duv0dy";
        case GeomBinding::P: return "P";
        case GeomBinding::N: return "N";
        case GeomBinding::Ng: return "Ng";
        case GeomBinding::T: return "T";
        case GeomBinding::TSign: return "Tsign";
        case GeomBinding::NdotV: return "NdotV";
        case GeomBinding::DNDX: return "dNdx";
        case GeomBinding::DNDY: return "dNdy";
        case GeomBinding::PixelDUVDX: return "duv0dx_pixel";
        case GeomBinding::PixelDUVDY: return "duv0dy_pixel";
        case GeomBinding::PixelDNDX: return "dNdx_pixel";
        case GeomBinding::PixelDNDY: return "dNdy_pixel";
        case GeomBinding::FrontFacing: return "front_facing";
    }
    return "";
}

TypeDesc bindingType(GeomBinding b) {
    switch (b) {
        case GeomBinding::UV:
        case GeomBinding::DUVDX:
        case GeomBinding::DUVDY:
        case GeomBinding::PixelDUVDX:
        case GeomBinding::PixelDUVDY: return TypeDesc::Vec2;
        case GeomBinding::P:
        case GeomBinding::DNDX:
        case GeomBinding::DNDY:
        case GeomBinding::PixelDNDX:
        case GeomBinding::PixelDNDY:
        case GeomBinding::T: return TypeDesc::Vector3;
        case GeomBinding::N:
        case GeomBinding::Ng: return TypeDesc::Normal3;
        case GeomBinding::TSign:
        case GeomBinding::NdotV:
        case GeomBinding::FrontFacing:
        case GeomBinding::None: return TypeDesc::Float;
    }
    return TypeDesc::Float;
}

const char* bindingGlsl(GeomBinding b) {
    switch (b) {
        case GeomBinding::None: return "";
        case GeomBinding::UV: return "s.uv";
        case GeomBinding::DUVDX: return "s.duvdx";
        case GeomBinding::DUVDY: return "s.duvdy";
        case GeomBinding::P: return "s.position";
        case GeomBinding::N: return "s.normal";
        case GeomBinding::Ng: return "s.geometric_normal";
        case GeomBinding::T: return "s.tangent.xyz";
        case GeomBinding::TSign: return "s.tangent.w";
        case GeomBinding::NdotV: return "dot(s.normal, q.wo)";
        case GeomBinding::DNDX: return "s.dNdx";
        case GeomBinding::DNDY: return "s.dNdy";
        case GeomBinding::PixelDUVDX: return "s.duvdx";
        case GeomBinding::PixelDUVDY: return "s.duvdy";
        case GeomBinding::PixelDNDX: return "s.dNdx";
        case GeomBinding::PixelDNDY: return "s.dNdy";
        case GeomBinding::FrontFacing: return "(s.front_facing ? 1.0 : 0.0)";
    }
    return "";
}

bool isDerivativeBinding(GeomBinding b) {
    switch (b) {
        case GeomBinding::DUVDX:
        case GeomBinding::DUVDY:
        case GeomBinding::DNDX:
        case GeomBinding::DNDY:
        case GeomBinding::PixelDUVDX:
        case GeomBinding::PixelDUVDY:
        case GeomBinding::PixelDNDX:
        case GeomBinding::PixelDNDY: return true;
        case GeomBinding::None:
        case GeomBinding::UV:
        case GeomBinding::P:
        case GeomBinding::N:
        case GeomBinding::Ng:
        case GeomBinding::T:
        case GeomBinding::TSign:
        case GeomBinding::NdotV:
        case GeomBinding::FrontFacing: return false;
    }
    return true;
}

int NodeSpec::inputIndex(const std::string& n) const {
    for (size_t i = 0; i < inputs.size(); ++i)
        if (inputs[i].name == n) return int(i);
    return -1;
}
int NodeSpec::outputIndex(const std::string& n) const {
    for (size_t i = 0; i < outputs.size(); ++i)
        if (outputs[i].name == n) return int(i);
    return -1;
}
std::vector<std::string> NodeSpec::inputNames() const {
    std::vector<std::string> r;
    for (auto& p : inputs) r.push_back(p.name);
    return r;
}
std::vector<std::string> NodeSpec::outputNames() const {
    std::vector<std::string> r;
    for (auto& p : outputs) r.push_back(p.name);
    return r;
}

NodeRegistry& NodeRegistry::instance() {
    static NodeRegistry r;
    static std::once_flag builtins;  // explicit, idempotent and thread-safe: no static-initialisation order
    std::call_once(builtins, [] { addBuiltinNodes(r); });
    return r;
}

void NodeRegistry::add(NodeSpec spec) {
    if (specs_.count(spec.id) || spec.inputs.size() > size_t(kMaxInputs) || spec.outputs.size() > size_t(kMaxOutputs)) {
        std::fprintf(stderr, "specula: invalid or duplicate node registration '%s'\n", spec.id.c_str());
        std::abort();
    }
    std::string id = spec.id;
    specs_[id] = std::make_unique<NodeSpec>(std::move(spec));
}

const NodeSpec* NodeRegistry::find(const std::string& id) const {
    auto it = specs_.find(id);
    return it == specs_.end() ? nullptr : it->second.get();
}

std::vector<std::string> NodeRegistry::ids() const {
    std::vector<std::string> r;
    for (auto& [k, v] : specs_) r.push_back(k);
    return r;
}

std::vector<const NodeSpec*> NodeRegistry::all() const {
    std::vector<const NodeSpec*> r;
    for (auto& [k, v] : specs_) r.push_back(v.get());
    return r;
}

const char* resourceKindName(ResourceSpec::Kind k) {
    switch (k) {
        case ResourceSpec::Kind::ImageFile: return "image_file";
        case ResourceSpec::Kind::DerivedImage: return "derived_image";
        case ResourceSpec::Kind::BuiltinTable: return "builtin_table";
    }
    return "?";
}

void nodeParamsFatal(const std::string& what) {
    std::fprintf(stderr, "specula: node declaration error: %s\n", what.c_str());
    std::abort();
}

namespace {
size_t preparePort(const NodeSpec* spec, const std::string& port) {
    int k = spec ? spec->inputIndex(port) : -1;
    if (k < 0) nodeParamsFatal("prepare reads unknown port '" + port + "' of " + (spec ? spec->id : std::string("?")));
    return size_t(k);
}
}  // namespace

const std::string& PrepareContext::str(const std::string& port) const { return (*strings)[preparePort(spec, port)]; }
const std::string& PrepareContext::pointer(const std::string& port) const { return pointers[preparePort(spec, port)]; }

std::array<float, 3> PrepareContext::number3(const std::string& port) const {
    const size_t k = preparePort(spec, port);
    const PortSpec& p = spec->inputs[k];
    if (!p.uniform || p.type == TypeDesc::String || p.type == TypeDesc::Closure)
        nodeParamsFatal("prepare reads '" + port + "' of " + spec->id + ", which is not a uniform numeric input");
    return values && k < values->size() ? (*values)[k] : p.def;
}
float PrepareContext::number(const std::string& port) const { return number3(port)[0]; }

}  // namespace specula::graph
