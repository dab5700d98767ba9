// Node declarations: PortSpec/NodeSpec (declared once, in C++, per node file), the flat CPU
// instruction format the compiled graph runs, and the self-registering NodeRegistry.
#pragma once

#include "core/graph/types.h"
#include "core/math/math.h"

#include <array>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace specula {
struct ShadingPoint;
class ScratchArena;
class Closure;
struct GraphLoadContext;
}  // namespace specula

namespace specula::graph {

// Default geometric source of an unconnected input (MaterialX-style default geometric binding).
// CPU reads the ShadingPoint, GLSL the SpeculaShadingInputs struct (docs/graph-format.md).
enum class GeomBinding : uint8_t {
    None,
    UV,      // vec2    sp.uv           s.uv
    DUVDX,   // vec2    sp.duvdx        s.duvdx
    DUVDY,   // vec2    sp.duvdy        s.duvdy
    P,       // vector3 sp.p            s.position
    N,       // normal3 sp.n            s.normal
    Ng,      // normal3 sp.ng           s.geometric_normal
    T,       // vector3 sp.tangent.xyz  s.tangent.xyz
    TSign,   // float   sp.tangent.w    s.tangent.w
    NdotV,   // float   dot(sp.n, sp.wo)  dot(s.normal, q.wo)
    DNDX,    // vector3 sp.dndx         s.dNdx   (screen derivative of the surface's shading normal)
    DNDY,    // vector3 sp.dndy         s.dNdy
    // One whole pixel step whatever the spp (the CPU differentials divided by sp.differentialScale; on a GPU the
    // derivatives are per pixel already): footprints that are a property of the image, e.g. the glint LOD.
    PixelDUVDX,  // vec2    sp.duvdx / scale.x   s.duvdx
    PixelDUVDY,  // vec2    sp.duvdy / scale.y   s.duvdy
    PixelDNDX,   // vector3 sp.dndx / scale.x    s.dNdx
    PixelDNDY,   // vector3 sp.dndy / scale.y    s.dNdy
    FrontFacing, // float   sp.frontFacing (1/0)  s.front_facing (1/0): the ray arrived on the side the normal points to
};
const char* bindingName(GeomBinding b);
TypeDesc bindingType(GeomBinding b);
const char* bindingGlsl(GeomBinding b);
// Whether the binding is a screen-space differential (its value needs the shading point's derivatives).
bool isDerivativeBinding(GeomBinding b);
// loadBinding (the value of a binding at a shading point): core/graph/load_binding.h.

// Value names of a typed enum port and the prefix of its generated GLSL constants (node_params.h, SPECULA_ENUM).
struct EnumDesc {
    std::string glslPrefix;           // e.g. "SPC_FRESNEL": constants SPC_FRESNEL_SCHLICK = 0, ...
    std::vector<std::string> values;  // the first is the default
};

struct PortSpec {
    std::string name;
    TypeDesc type = TypeDesc::Float;
    std::array<float, 3> def{0.f, 0.f, 0.f};   // numeric default (first typeWidth entries)
    std::string defString;                      // default of a string port ("" + required = must be given)
    std::vector<std::string> enumValues;        // non-empty: string port restricted to these (GLSL gets the index)
    const EnumDesc* enumDesc = nullptr;         // the typed enum behind enumValues (GLSL constants), if declared
    float minValue = -std::numeric_limits<float>::infinity();  // documented typical range; the parity suite
    float maxValue = std::numeric_limits<float>::infinity();   // samples inputs inside it
    float softMin = -std::numeric_limits<float>::infinity();   // soft range: a literal outside is valid but warns
    float softMax = std::numeric_limits<float>::infinity();    // (e.g. an albedo above 1 creates energy)
    float hardMin = -std::numeric_limits<float>::infinity();   // hard range: a literal outside is an error
    float hardMax = std::numeric_limits<float>::infinity();
    std::string doc;
    GeomBinding binding = GeomBinding::None;
    bool required = false;  // no default: must be connected (closures) or given (strings)
    bool uniform = false;   // one value per material, never per shading point (sampler state, derivative mode):
                            // connections are refused, and GLSL may rely on uniform control flow
    // Connected or non-zero, the node's result turns with the tangent (anisotropy): on a mesh without uvs the tangent
    // is an arbitrary direction, and the scene loader warns (ports bound to GeomBinding::UV warn by themselves).
    bool orientsByTangent = false;

    // Fluent construction used by the node files.
    static PortSpec make(std::string n, TypeDesc t, std::array<float, 3> d, std::string doc_) {
        PortSpec p;
        p.name = std::move(n);
        p.type = t;
        p.def = d;
        p.doc = std::move(doc_);
        return p;
    }
    static PortSpec f(std::string n, float d, std::string doc_) { return make(std::move(n), TypeDesc::Float, {d, 0, 0}, std::move(doc_)); }
    static PortSpec v2(std::string n, Vec2 d, std::string doc_) { return make(std::move(n), TypeDesc::Vec2, {d.x, d.y, 0}, std::move(doc_)); }
    static PortSpec c3(std::string n, Vec3 d, std::string doc_) { return make(std::move(n), TypeDesc::Color3, {d.x, d.y, d.z}, std::move(doc_)); }
    static PortSpec v3(std::string n, Vec3 d, std::string doc_) { return make(std::move(n), TypeDesc::Vector3, {d.x, d.y, d.z}, std::move(doc_)); }
    static PortSpec n3(std::string n, Vec3 d, std::string doc_) { return make(std::move(n), TypeDesc::Normal3, {d.x, d.y, d.z}, std::move(doc_)); }
    static PortSpec closure(std::string n, std::string doc_) {
        PortSpec p = make(std::move(n), TypeDesc::Closure, {0, 0, 0}, std::move(doc_));
        p.required = true;
        return p;
    }
    static PortSpec str(std::string n, std::string doc_) {
        PortSpec p = make(std::move(n), TypeDesc::String, {0, 0, 0}, std::move(doc_));
        p.required = true;
        return p;
    }
    static PortSpec choice(std::string n, std::vector<std::string> values, std::string doc_) {
        PortSpec p = make(std::move(n), TypeDesc::String, {0, 0, 0}, std::move(doc_));
        p.defString = values.front();
        p.enumValues = std::move(values);
        return p;
    }
    static PortSpec out(std::string n, TypeDesc t, std::string doc_) { return make(std::move(n), t, {0, 0, 0}, std::move(doc_)); }
    PortSpec&& range(float lo, float hi) && {
        minValue = lo;
        maxValue = hi;
        return std::move(*this);
    }
    PortSpec&& bind(GeomBinding b) && {
        binding = b;
        return std::move(*this);
    }
};

// Texels of a GPU resource as a host uploads them: RGBA32F levels (level 0 first), rows bottom-up, and the sampler
// state the node's GLSL expects. 2D arrays (sampler2DArray, GL_TEXTURE_2D_ARRAY): every level has the same 'layers'
// and holds them one after the other (layer 0 first), as glTexImage3D reads them.
struct ResourceImage {
    struct Level {
        int width = 0, height = 0;  // height = layer count for 1D arrays
        int layers = 1;             // 2D arrays: the layer count (1 otherwise)
        std::vector<float> rgba;    // width * height * layers * 4 floats
    };
    std::vector<Level> levels;
    std::string colorspace = "raw";  // the colour space of the texel values ("raw": data)
    bool generateMipmaps = false;    // only level 0 is given: the host builds the MIP chain (glGenerateMipmap)
    std::string minFilter = "linear_mipmap_linear", magFilter = "linear";  // GL names: nearest, linear, *_mipmap_*
    std::string wrapS = "repeat", wrapT = "repeat";                        // repeat, clamp_to_edge, mirrored_repeat
};

// A GPU resource a node's GLSL function takes as a parameter (MaterialX's resource binding context): the emitter
// declares it with a binding, lists it in GlslModule::resources, and hosts and tests bind from that manifest.
struct ResourceSpec {
    enum class Kind : uint8_t {
        ImageFile,     // an image file with its colour space (texture.image)
        DerivedImage,  // computed from a file on load (the LEAN moment pyramid)
        BuiltinTable,  // a table built into Specula (the glint dictionary, later the LTC fits)
    };
    std::string name;      // the GLSL parameter name, e.g. "tex"
    std::string glslType;  // sampler2D, sampler1DArray, ...
    Kind kind = Kind::ImageFile;
    std::string doc;
    // The texels for a node instance, from its prepared data (PrepareFn result; null for built-in tables).
    ResourceImage (*produce)(const void* prepared) = nullptr;
    std::string fileInput, colorspaceInput;  // ImageFile/DerivedImage: the string inputs naming the file, its colour space
};
const char* resourceKindName(ResourceSpec::Kind k);

struct Instr;
struct EvalContext;
// CPU entry of a node: reads its input registers, writes its output registers.
using CpuFn = void (*)(EvalContext& ctx, const Instr& ins);
// The same for a batch of shading points (Program::shadeBatch: one call per node per batch, issue 37): ctx[k] is the
// k-th point's context. Must compute exactly what n calls of the node's CpuFn compute, in any order of the points.
using CpuBatchFn = void (*)(EvalContext* ctx, size_t n, const Instr& ins);

// Per-instance preparation (string/enum literals and uniform numeric literals -> opaque data such as a texture handle
// or tables fitted for one roughness).
struct NodeSpec;
struct PrepareContext {
    const NodeSpec* spec = nullptr;
    const std::vector<std::string>* strings;  // per input port; "" for non-string ports
    const GraphLoadContext* load;             // may be null (e.g. codegen-only use)
    std::vector<std::string> pointers;        // JSON pointer per input port (for errors)
    // Per input port: the literal (or default) numeric value, meaningful for PortSpec::uniform ports only (those can
    // never be connected, so their value is known before any shading point). Null: the ports' defaults.
    const std::vector<std::array<float, 3>>* values = nullptr;
    // The string literal and the JSON pointer of the input port named 'port' (aborts on an unknown name: a
    // programming error found by every test).
    const std::string& str(const std::string& port) const;
    const std::string& pointer(const std::string& port) const;
    // The value of a uniform numeric input (first component; number3 all three). Aborts for an unknown port or one
    // that is not uniform: a per-shading-point input has no value at prepare time.
    float number(const std::string& port) const;
    std::array<float, 3> number3(const std::string& port) const;
};
using PrepareFn = std::shared_ptr<const void> (*)(const PrepareContext& ctx);

enum NodeFlags : uint32_t {
    kPure = 1u << 0,              // outputs depend only on inputs: folded when all inputs are constant
    kNeedsDerivatives = 1u << 1,  // reads screen-space differentials (sp.dpdx..., GLSL dFdx/dFdy)
    kEmissive = 1u << 2,          // can produce emission
    kReadsUv = 1u << 3,           // reads the surface's uvs (or the tangent made from them) without a uv input port
};

// Where a node's parameter struct keeps each port (built by NodeParams<P>): Program::compile fills a copy of the struct
// with every port that is constant in the program, once, so a shade copies that block and reads only the ports that
// vary per shading point (issue 15: the per-port read loop was a third of a GGX node's time).
struct ParamField {
    enum Kind : uint8_t { Floats, Enum, Closure };
    uint16_t offset;
    uint8_t width;
    Kind kind;
    uint8_t port;
    GeomBinding binding;  // the port's default geometry binding (NodeParams::bind), None if it has none
};
struct ParamLayout {
    size_t size = 0, align = 1;
    std::vector<ParamField> fields;
};
// One member of a node's parameter struct that varies per shading point, as Program::compile resolved it: after the
// pre-read block (Instr::constParams), NodeParams::read copies 'width' floats into the member at 'offset' from register
// 'source', or from the shading point's bytes at 'source' (a binding that is a field of ShadingPoint), or computes it
// with loadBinding (NdotV, the pixel footprints, frontFacing). No per-port look-up, bit test or binding switch remains
// per shade (issue 37: a third of the GGX node's extra instructions in bench_graph).
struct ParamRead {
    enum From : uint8_t { Register, ShadingPointBytes, Binding };
    uint16_t offset;
    uint16_t source;
    uint8_t width;
    From from;
    GeomBinding binding;
};

struct NodeSpec {
    std::string id;        // stable, e.g. "bsdf.ggx"
    int version = 1;
    std::string category;  // family: constant, geometry, texture, math, convert, fresnel, bsdf, closure
    std::string doc;
    // Implementation notes for the reference page (docs/nodes.md, `specula nodes`): the formula, the papers and the
    // CPU and GLSL homes of the model, where the one-line doc has no room for them. Empty: none.
    std::string notes;
    std::vector<PortSpec> inputs, outputs;
    std::vector<ResourceSpec> resources;  // GPU resources of the GLSL function, in parameter-name order
    uint32_t flags = 0;
    CpuFn cpu = nullptr;
    // Optional batch entry of cpu (nodes/node_common.h batchOf<&cpu>: the node's function inlined into one loop over
    // the points, so consecutive points' latency chains overlap). Null: Program::shadeBatch calls cpu per point.
    CpuBatchFn cpuBatch = nullptr;
    PrepareFn prepare = nullptr;
    std::string glslFunction;  // GLSL function name (overloads allowed across typed variants)
    std::string glslFile;      // path of the .glsl relative to nodes/ (embedded into the binary)
    // Shared GLSL files (paths relative to nodes/, e.g. "shared/ltc.glsl") that glslFile calls into: the emitter and
    // the GLSL tests put each one once per module, include-guarded, before the node files (codegen::glslLibraryText).
    std::vector<std::string> glslLibraries;
    float parityTolerance = 1e-4f;  // max relative error CPU vs GLSL (docs/nodes.md)
    std::string parityNote;         // why a looser tolerance is needed
    // A node whose CPU model cannot run on the GPU declares it here: gpuSubstitute says in one sentence what its GLSL
    // function computes instead (the emitter warns with it once per module, docs/nodes.md shows it), and
    // gpuSubstituteCpu is the CPU twin of that GLSL function, which the parity suite compares it against (cpu stays
    // the model the renderer uses). A node whose GLSL is its model less a CPU-only option (bsdf.glint's integrated
    // quad lights) sets gpuSubstituteCpu alone: the raster integrator and the parity suite then run what the GLSL
    // computes, and the emitter has nothing to warn about.
    std::string gpuSubstitute;
    CpuFn gpuSubstituteCpu = nullptr;
    // The parameter struct that cpu (and gpuSubstituteCpu) read with NodeParams<P>::read, or null (the node reads its
    // registers itself). Set by NodeParams<P>::describe.
    const ParamLayout* params = nullptr;

    bool has(uint32_t f) const { return (flags & f) != 0; }
    int inputIndex(const std::string& n) const;
    int outputIndex(const std::string& n) const;
    std::vector<std::string> inputNames() const;
    std::vector<std::string> outputNames() const;
    // GLSL source text of glslFile (embedded), or nullptr if missing.
    const std::string* glslSource() const;
    // The GLSL prototype bound to the ports by name (codegen::bindGlslFunction), with parameter names:
    // "void fn(SpeculaClosureQuery q, vec3 weight, ..., out SpeculaClosure bsdf)", or "(unbound: why)".
    std::string glslPrototype() const;
};

// ---- flat instruction list ---------------------------------------------------------------------
constexpr size_t kMaxRegisters = 65535;  // Instr's register indices are uint16_t (Program::compile refuses more)
constexpr int kMaxInputs = 32;  // bsdf.glint has 29 inputs (22 + the fresnelPorts() group, base_color and derivatives)
constexpr int kMaxOutputs = 6;  // geometry.uv has 5 (uv, sample and pixel footprints); usedOutputs holds 8 bits
constexpr uint16_t kNoRegister = 0xFFFF;

// One compiled node: entry point + register offsets. For string ports in[k] is unused (kNoRegister),
// for enum ports in[k] holds the chosen enum index directly.
struct Instr {
    CpuFn fn = nullptr;
    CpuBatchFn batchFn = nullptr;  // NodeSpec::cpuBatch when fn is NodeSpec::cpu; else null (fn per point)
    const void* data = nullptr;  // prepared per-instance data (PrepareFn), owned by the program
    uint16_t in[kMaxInputs];
    uint16_t out[kMaxOutputs];
    uint8_t usedOutputs = 0xFF;  // bit k: output k is read by another node or is a root (lazy outputs may skip work)
    // The node's parameter struct with every port that is constant in the program already read (layout
    // NodeSpec::params; owned by the program), and the input ports (bit k) that vary per shading point. Null: read all.
    const void* constParams = nullptr;
    const ParamLayout* constLayout = nullptr;
    uint32_t dynamicPorts = 0xFFFFFFFFu;
    // Of the dynamic ports, those fed by their own geometry binding (PortSpec::binding): NodeParams::read takes them
    // from the shading point itself, so no register (and no prologue load) stands between the two.
    uint32_t boundPorts = 0;
    // The dynamic ports' reads, in port order (owned by the program; ParamRead): what NodeParams::read does after
    // copying constParams.
    const ParamRead* reads = nullptr;
    uint8_t readCount = 0;
};

// Per-evaluation state the instruction functions see.
struct EvalContext {
    float* r = nullptr;                 // register file
    const float* constants = nullptr;   // the program's register template (closure pool indices live there)
    const ShadingPoint* sp = nullptr;   // null while constant folding
    ScratchArena* arena = nullptr;      // lobes are allocated here
    Closure* const* closures = nullptr; // closure pool: a closure register holds an index into it
    Color3* emission = nullptr;         // emission per closure pool entry
};

// ---- registry ------------------------------------------------------------------------------------
class NodeRegistry {
public:
    static NodeRegistry& instance();
    void add(NodeSpec spec);  // aborts on duplicate id (a programming error, found by every test)
    const NodeSpec* find(const std::string& id) const;
    std::vector<std::string> ids() const;           // sorted
    std::vector<const NodeSpec*> all() const;       // sorted by id
    // What the nodes of a category share (the notes under its heading in docs/nodes.md), declared once per category
    // in the category's own folder (nodes/<category>/category.cpp). Empty for an undescribed category.
    void describeCategory(const std::string& category, std::string notes) { categoryNotes_[category] = std::move(notes); }
    const std::string& categoryNotes(const std::string& category) const {
        static const std::string kNone;
        auto it = categoryNotes_.find(category);
        return it == categoryNotes_.end() ? kNone : it->second;
    }

private:
    std::map<std::string, std::unique_ptr<NodeSpec>> specs_;
    std::map<std::string, std::string> categoryNotes_;
};

struct NodeRegistrar {
    explicit NodeRegistrar(void (*fn)(NodeRegistry&)) { fn(NodeRegistry::instance()); }
};

#define SPECULA_NODE_CONCAT2(a, b) a##b
#define SPECULA_NODE_CONCAT(a, b) SPECULA_NODE_CONCAT2(a, b)
// One per node file: SPECULA_REGISTER_NODES(fn) with fn(NodeRegistry&) adding its spec(s).
// In libspecula the build defines SPECULA_NODE_UNIT per node file: the macro then defines the file's
// extern "C" registration function, which the generated builtin_nodes.cpp calls from addBuiltinNodes()
// (no static initialiser). Without SPECULA_NODE_UNIT it registers at static-initialisation time.
#ifdef SPECULA_NODE_UNIT
#define SPECULA_REGISTER_NODES(fn)                                                                            \
    extern "C" void SPECULA_NODE_CONCAT(specula_register_nodes_, SPECULA_NODE_UNIT)(::specula::graph::NodeRegistry & r) { \
        fn(r);                                                                                                \
    }                                                                                                         \
    static_assert(true, "")
#else
#define SPECULA_REGISTER_NODES(fn) \
    static ::specula::graph::NodeRegistrar SPECULA_NODE_CONCAT(specula_node_registrar_, __LINE__)(fn)
#endif

// Adds every built-in node (generated by the build from the node files); called once by instance().
void addBuiltinNodes(NodeRegistry& r);

}  // namespace specula::graph
