// Graph JSON -> validated GraphDesc (types, references, cycles, with JSON pointers in every error)
// -> Program: a flat instruction list over a float register file, constant-folded and pruned.
#pragma once

#include "core/graph/node_spec.h"
#include "core/render/bsdf.h"
#include "core/render/shading.h"

#include <nlohmann/json_fwd.hpp>

#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace specula::graph {

// How one input port of a node instance gets its value.
struct InputValue {
    enum class Kind : uint8_t { Default, Literal, Connection, Binding };
    Kind kind = Kind::Default;
    std::array<float, 3> value{0.f, 0.f, 0.f};  // numeric literal/default
    std::string str;                            // string literal/default
    int enumIndex = -1;                         // for enum string ports
    int srcNode = -1, srcPort = -1;             // connection source (index into GraphDesc::nodes, output port)
    std::string pointer;                        // JSON pointer of the value (or of where it would go)
};

struct NodeInstance {
    std::string id;
    const NodeSpec* spec = nullptr;
    std::vector<InputValue> inputs;  // one per spec->inputs
    std::string pointer;             // JSON pointer of the node object
};

struct GraphDesc {
    std::string pointer;               // JSON pointer of the material object
    std::vector<NodeInstance> nodes;   // sorted by id
    std::vector<int> order;            // topological order (sources first), deterministic
    int outputNode = -1, outputPort = -1;
    // Literals outside a port's soft range (documented range): "<JSON pointer>: <message>", in node order.
    std::vector<std::string> warnings;
    int findNode(const std::string& id) const;
    // Nodes reachable from the given (node, port) roots, in topological order (dead nodes pruned).
    std::vector<int> liveOrder(const std::vector<std::pair<int, int>>& roots) const;
};

struct ParseOptions {
    bool requireClosureOutput = true;  // materials: yes; tests/tools may compile pattern graphs
};

// Validates a graph {"nodes": {...}, "output": "@node.port"}; throws specula::InputError naming the
// JSON pointer (pointer = location of 'material') and a nearest-name suggestion where one exists.
GraphDesc parseGraph(const nlohmann::json& material, const std::string& pointer, const ParseOptions& opt = {});

// Compiled, immutable, thread-safe evaluation program.
class Program {
public:
    // roots[0] is the material output; more roots keep extra outputs alive (tests, tools).
    static Program compile(const GraphDesc& g, const std::vector<std::pair<int, int>>& roots,
                           const GraphLoadContext* load);

    // Runs the program at sp (never modified). If 'out' is given it receives the closure of roots[0]
    // (closure-typed); 'emission' receives that closure's emission. Returns the register file (valid until the
    // arena is reset).
    const float* run(const ShadingPoint& sp, ScratchArena& arena, Closure* out, Color3* emission) const;
    // Same as run() for the renderer's hot path: registers and the closure pool live on the stack
    // when small (no arena traffic besides the lobes).
    void shade(const ShadingPoint& sp, ScratchArena& arena, Closure* out, Color3* emission) const;
    // shade() of n points in one pass over the instructions (issue 37 item 1): each node runs once per batch (its
    // NodeSpec::cpuBatch, or its cpu per point), so the interpreter's frame is paid per batch, not per point. Computes
    // exactly what shade(*sps[k], arena, out[k], emission ? &emission[k] : nullptr) computes for every k; all lobes
    // go to 'arena'.
    void shadeBatch(const ShadingPoint* const* sps, size_t n, ScratchArena& arena, Closure* const* out,
                    Color3* emission) const;

    uint16_t rootRegister(size_t i) const { return rootRegs_[i]; }
    size_t instructionCount() const { return code_.size(); }
    size_t foldedCount() const { return folded_; }
    size_t registerCount() const { return tmpl_.size(); }
    size_t closureSlots() const { return slots_; }
    bool emissive() const { return emissive_; }
    // Some live node reads screen-space differentials (kNeedsDerivatives) or a port bound to one (Material::needsDerivatives).
    bool needsDerivatives() const { return needsDerivatives_; }
    // What a shade does besides running the nodes: geometry bindings loaded into registers (those not read from the
    // shading point directly, Instr::boundPorts), and whether it copies the register template first.
    size_t prologueLoads() const { return prologue_.size(); }
    bool readsTemplate() const { return readsTemplate_; }

private:
    // Fills ins.constParams with the ports of 'layout' that are constant in this program (Instr::constParams).
    void preRead(Instr& ins, const ParamLayout& layout, uint32_t dynamicPorts);
    // The registers, closure pool and context of one shade at sp, before the first instruction (execute, shadeBatch).
    EvalContext prepare(const ShadingPoint& sp, ScratchArena& arena, float* r, Closure** cl, Color3* em, Closure* out,
                        bool wholeRegisterFile) const;
    // wholeRegisterFile: run() hands the registers out, so the template is copied even where no instruction reads it.
    void execute(const ShadingPoint& sp, ScratchArena& arena, float* r, Closure** cl, Color3* em, Closure* out, Color3* emission,
                 bool wholeRegisterFile) const;
    struct Load {
        GeomBinding binding;
        uint16_t reg;
    };
    std::vector<float> tmpl_;
    std::vector<Instr> code_;
    std::vector<Load> prologue_;
    std::vector<std::shared_ptr<const void>> data_;
    std::vector<uint16_t> rootRegs_;
    int outSlot_ = -1;
    size_t slots_ = 0, folded_ = 0;
    bool emissive_ = false;
    bool needsDerivatives_ = false;
    // Whether a shade copies the template: false only when every instruction has a parameter struct and every port that
    // varies is a direct binding (a conservative test: ports fed by other nodes also set it; see compile).
    bool readsTemplate_ = false;
    // The program is one node whose closure is the material's output, with no prologue, no template read and registers
    // that fit shade()'s stack (a BSDF node with literal inputs, the commonest material): shade and shadeBatch then call
    // it without the closure pool, prologue and instruction loops (issue 37: bench_graph's per-point set-up).
    bool singleClosureNode_ = false;
};

}  // namespace specula::graph
