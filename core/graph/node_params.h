// Named node parameters (OSL closure-parameter tables, BSDL style): a node declares a plain parameter struct and one
// list binding each member to its port; PortSpecs, the typed CPU read and the GLSL enum constants all come from it.
#pragma once

#include "core/graph/load_binding.h"
#include "core/graph/node_spec.h"

#include <array>
#include <cstddef>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

namespace specula::graph {

// A closure-typed port's value: an index into the program's closure pool.
struct ClosureRef {
    int slot = -1;
};

// The value of a width-generic port (math.add.<type> etc.): W floats.
template <int W>
using FloatN = std::array<float, W>;

// Typed enums: a specialisation of EnumInfo<E> names the values (in order, the first is the default) and the prefix
// of the GLSL constants generated for them (SPC_FRESNEL_SCHLICK = 0, ...). Declare with SPECULA_ENUM.
template <class E>
struct EnumInfo;

#define SPECULA_ENUM(Type, glslPrefix, ...)                                     \
    template <>                                                                 \
    struct specula::graph::EnumInfo<Type> {                                      \
        static const ::specula::graph::EnumDesc& desc() {                        \
            static const ::specula::graph::EnumDesc d{glslPrefix, {__VA_ARGS__}}; \
            return d;                                                            \
        }                                                                        \
    }

// A typed output port of a node: its index comes from the order of declaration in an OutputList.
template <class T>
struct OutPort {
    uint8_t index;
};

// Output declarations of one node; handles are typed so a write of the wrong type cannot compile.
class OutputList {
public:
    template <class T>
    OutPort<T> add(std::string name, TypeDesc t, std::string doc) {
        static_assert(std::is_same_v<T, float> || std::is_same_v<T, Vec2> || std::is_same_v<T, Vec3> ||
                          std::is_same_v<T, ClosureRef> || std::is_same_v<T, FloatN<1>> || std::is_same_v<T, FloatN<2>> ||
                          std::is_same_v<T, FloatN<3>>,
                      "output values are float, Vec2, Vec3, FloatN<W> or ClosureRef");
        ports_.push_back(PortSpec::out(std::move(name), t, std::move(doc)));
        return OutPort<T>{uint8_t(ports_.size() - 1)};
    }
    const std::vector<PortSpec>& ports() const { return ports_; }

private:
    std::vector<PortSpec> ports_;
};

// Writes an output value.
template <class T>
inline void set(EvalContext& c, const Instr& i, OutPort<T> o, const T& v) {
    static_assert(sizeof(T) % sizeof(float) == 0 && !std::is_same_v<T, ClosureRef>, "numeric outputs only");
    std::memcpy(c.r + i.out[o.index], &v, sizeof(T));
}
// Whether output o is read by another node or is a program root: lazy outputs (e.g. texture gradients) skip work.
template <class T>
inline bool wanted(const Instr& i, OutPort<T> o) {
    return (i.usedOutputs >> o.index) & 1;
}
// The closure (and its emission) of a closure output.
// The pool index is fixed per program, so it is read from the register template: a shade that copies no template
// (Program::shade) still finds it.
inline int slotOf(const EvalContext& c, const Instr& i, OutPort<ClosureRef> o) { return int(c.constants[i.out[o.index]]); }

// Copies 'width' floats from src to dst: fixed-size copies for the widths ports have (1, 2 or 3), since a per-float
// loop was a third of a GGX node's time in bench_graph. Every port read of a parameter struct goes through it.
inline void copyPortFloats(char* dst, const void* src, int width) {
    switch (width) {
        case 1: std::memcpy(dst, src, 4); break;
        case 2: std::memcpy(dst, src, 8); break;
        case 3: std::memcpy(dst, src, 12); break;
        default: std::memcpy(dst, src, 4 * size_t(width)); break;
    }
}

// Reads port fd of instruction i from the registers r into the parameter struct at base. Program::compile uses it
// with the register template to pre-read the constant ports; NodeParams::read with the shade's registers.
inline void readParamField(const float* r, const Instr& i, const ParamField& fd, char* base) {
    switch (fd.kind) {
        case ParamField::Floats: copyPortFloats(base + fd.offset, r + i.in[fd.port], fd.width); break;
        case ParamField::Enum: {
            int v = int(i.in[fd.port]);
            std::memcpy(base + fd.offset, &v, sizeof v);
            break;
        }
        case ParamField::Closure: {
            ClosureRef ref{int(r[i.in[fd.port]])};
            std::memcpy(base + fd.offset, &ref, sizeof ref);
            break;
        }
    }
}

// The parameter list of a node with parameter struct P: builder calls bind members to ports in order.
template <class P>
class NodeParams {
    static_assert(std::is_trivially_copyable_v<P> && std::is_default_constructible_v<P>,
                  "a parameter struct is a plain record");
    static_assert(alignof(P) <= alignof(std::max_align_t), "Program::compile stores parameter blocks max_align_t-aligned");

public:
    NodeParams& f(std::string name, float P::*m, float def, std::string doc) {
        return numeric(std::move(name), offsetOf(m), TypeDesc::Float, {def, 0, 0}, std::move(doc));
    }
    NodeParams& v2(std::string name, Vec2 P::*m, Vec2 def, std::string doc) {
        return numeric(std::move(name), offsetOf(m), TypeDesc::Vec2, {def.x, def.y, 0}, std::move(doc));
    }
    NodeParams& c3(std::string name, Vec3 P::*m, Vec3 def, std::string doc) {
        return numeric(std::move(name), offsetOf(m), TypeDesc::Color3, {def.x, def.y, def.z}, std::move(doc));
    }
    NodeParams& v3(std::string name, Vec3 P::*m, Vec3 def, std::string doc) {
        return numeric(std::move(name), offsetOf(m), TypeDesc::Vector3, {def.x, def.y, def.z}, std::move(doc));
    }
    NodeParams& n3(std::string name, Vec3 P::*m, Vec3 def, std::string doc) {
        return numeric(std::move(name), offsetOf(m), TypeDesc::Normal3, {def.x, def.y, def.z}, std::move(doc));
    }
    // A width-generic port of type t (typeWidth(t) must be W; checked when the node registers).
    template <size_t W>
    NodeParams& typed(std::string name, std::array<float, W> P::*m, TypeDesc t, float def, std::string doc) {
        if (typeWidth(t) != int(W) || !isNumeric(t)) fatal("port '" + name + "' declared with a type of another width");
        return numeric(std::move(name), offsetOf(m), t, {def, def, def}, std::move(doc));
    }
    NodeParams& closure(std::string name, ClosureRef P::*m, std::string doc) {
        ports_.push_back(PortSpec::closure(std::move(name), std::move(doc)));
        addField(offsetOf(m), 1, ParamField::Closure);
        return *this;
    }
    template <class E>
    NodeParams& choice(std::string name, E P::*m, std::string doc) {
        static_assert(std::is_enum_v<E> && sizeof(E) == sizeof(int), "enum ports bind enum class E : int members");
        const EnumDesc& d = EnumInfo<E>::desc();
        PortSpec p = PortSpec::choice(std::move(name), d.values, std::move(doc));
        p.enumDesc = &d;
        ports_.push_back(std::move(p));
        addField(offsetOf(m), 1, ParamField::Enum);
        return *this;
    }
    // A string literal read by the node's prepare step only (file names, colour spaces): not in the struct.
    NodeParams& str(std::string name, std::string doc, std::string def = "") {
        PortSpec p = PortSpec::str(std::move(name), std::move(doc));
        if (!def.empty()) {
            p.defString = std::move(def);
            p.required = false;
        }
        ports_.push_back(std::move(p));
        return *this;
    }

    // Modifiers of the port declared last.
    NodeParams& range(float lo, float hi) {  // typical range: documented, and the parity suite samples it
        ports_.back().minValue = lo;
        ports_.back().maxValue = hi;
        return *this;
    }
    NodeParams& soft(float lo, float hi) {  // soft range: a literal outside it is valid but warns
        ports_.back().softMin = lo;
        ports_.back().softMax = hi;
        return *this;
    }
    NodeParams& hard(float lo, float hi) {  // hard range: a literal outside it is an error
        ports_.back().hardMin = lo;
        ports_.back().hardMax = hi;
        return *this;
    }
    NodeParams& uniform() {  // one value per material (sampler state, derivative mode): never connected
        ports_.back().uniform = true;
        return *this;
    }
    NodeParams& bind(GeomBinding b) {
        ports_.back().binding = b;
        if (!layout_.fields.empty() && layout_.fields.back().port == ports_.size() - 1) layout_.fields.back().binding = b;
        return *this;
    }
    NodeParams& orientsByTangent() {  // connected or non-zero, the result turns with the tangent (anisotropy)
        ports_.back().orientsByTangent = true;
        return *this;
    }

    const std::vector<PortSpec>& ports() const { return ports_; }

    // The node's ports and its parameter layout (NodeSpec::inputs, NodeSpec::params): the program may then pre-read
    // the constant ports (Instr::constParams).
    void describe(NodeSpec& s) const {
        s.inputs = ports_;
        s.params = &layout_;
    }

    // The typed read of every bound member from the instruction's registers: the program's pre-read block, if it
    // was built for this struct, and then only the ports that vary per shading point (Instr::reads).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
// GCC cannot see that a field's width is the width of its member once readParamField is inlined (field widths are
// checked when the port is declared).
#pragma GCC diagnostic ignored "-Warray-bounds"
#pragma GCC diagnostic ignored "-Wstringop-overflow"
#endif
    P read(const EvalContext& c, const Instr& i) const {
        P p;
        char* base = reinterpret_cast<char*>(&p);
        if (i.constLayout == &layout_) {
            std::memcpy(base, i.constParams, sizeof(P));
            for (const ParamRead *rd = i.reads, *end = i.reads + i.readCount; rd != end; ++rd) {
                char* dst = base + rd->offset;
                if (rd->from == ParamRead::Binding) {
                    loadBinding(rd->binding, *c.sp, reinterpret_cast<float*>(dst));
                    continue;
                }
                const char* src = rd->from == ParamRead::Register ? reinterpret_cast<const char*>(c.r + rd->source)
                                                                  : reinterpret_cast<const char*>(c.sp) + rd->source;
                copyPortFloats(dst, src, rd->width);
            }
            return p;
        }
        for (const ParamField& fd : layout_.fields) readParamField(c.r, i, fd, base);
        return p;
    }
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

private:
    void addField(size_t offset, uint8_t width, ParamField::Kind kind) {
        uint8_t port = uint8_t(ports_.size() - 1);
        if (port >= 32) fatal("more than 32 ports");
        layout_.fields.push_back({uint16_t(offset), width, kind, port, GeomBinding::None});
    }
    template <class M>
    static size_t offsetOf(M P::*m) {
        static const P probe{};
        return size_t(reinterpret_cast<const char*>(&(probe.*m)) - reinterpret_cast<const char*>(&probe));
    }
    NodeParams& numeric(std::string name, size_t offset, TypeDesc t, std::array<float, 3> def, std::string doc) {
        ports_.push_back(PortSpec::make(std::move(name), t, def, std::move(doc)));
        addField(offset, uint8_t(typeWidth(t)), ParamField::Floats);
        return *this;
    }
    [[noreturn]] static void fatal(const std::string& what);
    std::vector<PortSpec> ports_;
    ParamLayout layout_{sizeof(P), alignof(P), {}};
};

void nodeParamsFatal(const std::string& what);
template <class P>
void NodeParams<P>::fatal(const std::string& what) {
    nodeParamsFatal(what);
    std::abort();
}

}  // namespace specula::graph
