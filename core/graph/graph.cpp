// Graph validation (parseGraph), compilation to a flat instruction list (Program::compile) and the
// per-shading-point interpreter loop (Program::run).
#include "core/graph/graph.h"
#include "core/graph/node_params.h"

#include "core/graph/graph_material.h"
#include "core/util/error.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <functional>
#include <map>
#include <set>

namespace specula::graph {

using nlohmann::json;

int GraphDesc::findNode(const std::string& id) const {
    // parseGraph keeps the nodes sorted by id (a JSON object's order): binary search, since a linear one made parsing
    // quadratic (a 200k-node chain took 48 s). A hand-built, unsorted GraphDesc still finds its nodes linearly.
    auto it = std::lower_bound(nodes.begin(), nodes.end(), id, [](const NodeInstance& n, const std::string& k) { return n.id < k; });
    if (it != nodes.end() && it->id == id) return int(it - nodes.begin());
    for (size_t i = 0; i < nodes.size(); ++i)
        if (nodes[i].id == id) return int(i);
    return -1;
}

std::vector<int> GraphDesc::liveOrder(const std::vector<std::pair<int, int>>& roots) const {
    std::vector<char> live(nodes.size(), 0);
    std::vector<int> stack;
    for (auto& r : roots) stack.push_back(r.first);
    while (!stack.empty()) {
        int n = stack.back();
        stack.pop_back();
        if (n < 0 || live[n]) continue;
        live[n] = 1;
        for (auto& in : nodes[n].inputs)
            if (in.kind == InputValue::Kind::Connection) stack.push_back(in.srcNode);
    }
    std::vector<int> r;
    for (int n : order)
        if (live[n]) r.push_back(n);
    return r;
}

namespace {

std::string typeList(const std::vector<std::string>& v) {
    std::string s;
    for (size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + v[i];
    return s;
}

// Suggestion for an unknown node type: nearest registered id, or the typed variants of a family name.
std::string suggestType(const std::string& type) {
    auto ids = NodeRegistry::instance().ids();
    std::string best = nearestName(type, ids);
    if (!best.empty()) return best;
    for (auto& id : ids)
        if (id.rfind(type + ".", 0) == 0) return id;
    return "";
}

// A closure output in the graph other than 'exclude', preferring one no other node consumes.
std::string suggestClosureSource(const GraphDesc& g, int exclude) {
    std::vector<char> consumed(g.nodes.size(), 0);
    for (auto& n : g.nodes)
        for (auto& in : n.inputs)
            if (in.kind == InputValue::Kind::Connection && in.srcNode >= 0) consumed[in.srcNode] = 1;
    std::string any;
    for (size_t i = 0; i < g.nodes.size(); ++i) {
        if (int(i) == exclude || !g.nodes[i].spec) continue;
        for (auto& o : g.nodes[i].spec->outputs) {
            if (o.type != TypeDesc::Closure) continue;
            std::string ref = "@" + g.nodes[i].id + "." + o.name;
            if (!consumed[i]) return ref;
            if (any.empty()) any = ref;
        }
    }
    return any;
}

bool parseNumeric(const json& v, TypeDesc t, std::array<float, 3>& out) {
    int w = typeWidth(t);
    if (v.is_number()) {
        float x = v.get<float>();
        out = {x, w > 1 ? x : 0.f, w > 2 ? x : 0.f};
        return true;
    }
    if (v.is_array() && int(v.size()) == w) {
        out = {0.f, 0.f, 0.f};
        for (int i = 0; i < w; ++i) {
            if (!v[i].is_number()) return false;
            out[i] = v[i].get<float>();
        }
        return true;
    }
    return false;
}

std::string numberText(float v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}

// A literal outside the port's hard range is an error; outside its soft range, a warning.
void checkRange(const PortSpec& p, const NodeSpec& spec, const std::array<float, 3>& v, const std::string& ptr,
                std::vector<std::string>& warnings) {
    const int w = typeWidth(p.type);
    for (int c = 0; c < w; ++c) {
        const std::string where = w > 1 ? " (component " + std::to_string(c) + ")" : "";
        if (!(v[c] >= p.hardMin && v[c] <= p.hardMax))
            throw InputError(ptr, "value " + numberText(v[c]) + where + " of input '" + p.name + "' of " + spec.id +
                                      " is outside its valid range [" + numberText(p.hardMin) + ", " + numberText(p.hardMax) + "]",
                             numberText(std::clamp(v[c], p.hardMin, p.hardMax)));
        if (!(v[c] >= p.softMin && v[c] <= p.softMax)) {
            warnings.push_back(ptr + ": value " + numberText(v[c]) + where + " of input '" + p.name + "' of " + spec.id +
                               " is outside its usual range [" + numberText(p.softMin) + ", " + numberText(p.softMax) + "]");
            return;
        }
    }
}

}  // namespace

GraphDesc parseGraph(const json& mat, const std::string& pointer, const ParseOptions& opt) {
    GraphDesc g;
    g.pointer = pointer;
    if (!mat.is_object()) throw InputError(pointer, "a material must be a node-graph object {\"nodes\": {...}, \"output\": \"@node.port\"}");
    static const std::vector<std::string> kMatKeys = {"nodes", "output", "doc"};
    for (auto it = mat.begin(); it != mat.end(); ++it)
        if (std::find(kMatKeys.begin(), kMatKeys.end(), it.key()) == kMatKeys.end())
            throw InputError(pointer + "/" + pointerEscape(it.key()), "unknown material key '" + it.key() + "'",
                             nearestName(it.key(), kMatKeys));
    if (!mat.contains("nodes") || !mat["nodes"].is_object())
        throw InputError(pointer + "/nodes", "material graph needs a \"nodes\" object", "nodes");
    const json& nodes = mat["nodes"];
    const std::string np = pointer + "/nodes";

    // Pass 1: node ids and types.
    std::vector<std::string> ids;
    for (auto it = nodes.begin(); it != nodes.end(); ++it) ids.push_back(it.key());
    for (auto it = nodes.begin(); it != nodes.end(); ++it) {
        NodeInstance n;
        n.id = it.key();
        n.pointer = np + "/" + pointerEscape(n.id);
        const json& nj = it.value();
        if (!nj.is_object()) throw InputError(n.pointer, "a node must be an object {\"type\": ..., \"inputs\": {...}}");
        static const std::vector<std::string> kNodeKeys = {"type", "inputs", "doc"};
        for (auto k = nj.begin(); k != nj.end(); ++k)
            if (std::find(kNodeKeys.begin(), kNodeKeys.end(), k.key()) == kNodeKeys.end())
                throw InputError(n.pointer + "/" + pointerEscape(k.key()), "unknown node key '" + k.key() + "'",
                                 nearestName(k.key(), kNodeKeys));
        if (!nj.contains("type") || !nj["type"].is_string())
            throw InputError(n.pointer + "/type", "node '" + n.id + "' needs a string \"type\"");
        std::string type = nj["type"].get<std::string>();
        n.spec = NodeRegistry::instance().find(type);
        if (!n.spec) throw InputError(n.pointer + "/type", "unknown node type '" + type + "'", suggestType(type));
        g.nodes.push_back(std::move(n));
    }

    // Pass 2: inputs (literals, references, defaults, bindings).
    for (size_t ni = 0; ni < g.nodes.size(); ++ni) {
        NodeInstance& n = g.nodes[ni];
        const NodeSpec& spec = *n.spec;
        const json& nj = nodes[n.id];
        n.inputs.resize(spec.inputs.size());
        for (size_t k = 0; k < spec.inputs.size(); ++k) {
            const PortSpec& p = spec.inputs[k];
            InputValue& v = n.inputs[k];
            v.pointer = n.pointer + "/inputs/" + pointerEscape(p.name);
            v.value = p.def;
            v.str = p.defString;
            if (!p.enumValues.empty()) v.enumIndex = 0;
            v.kind = p.binding != GeomBinding::None ? InputValue::Kind::Binding : InputValue::Kind::Default;
        }
        if (nj.contains("inputs")) {
            const json& ins = nj["inputs"];
            if (!ins.is_object()) throw InputError(n.pointer + "/inputs", "\"inputs\" must be an object");
            for (auto it = ins.begin(); it != ins.end(); ++it) {
                std::string ip = n.pointer + "/inputs/" + pointerEscape(it.key());
                int k = spec.inputIndex(it.key());
                if (k < 0)
                    throw InputError(ip, "unknown input '" + it.key() + "' of " + spec.id + " (inputs: " + typeList(spec.inputNames()) + ")",
                                     nearestName(it.key(), spec.inputNames()));
                const PortSpec& p = spec.inputs[k];
                InputValue& v = n.inputs[k];
                const json& val = it.value();
                bool isRef = val.is_string() && !val.get<std::string>().empty() && val.get<std::string>()[0] == '@';
                if (isRef) {
                    if (p.type == TypeDesc::String)
                        throw InputError(ip, "input '" + p.name + "' of " + spec.id + " takes a literal string and cannot be connected");
                    if (p.uniform)
                        throw InputError(ip, "input '" + p.name + "' of " + spec.id + " is one value per material (uniform) and cannot be connected");
                    std::string ref = val.get<std::string>().substr(1);
                    size_t dot = ref.rfind('.');
                    std::string srcId = dot == std::string::npos ? ref : ref.substr(0, dot);
                    std::string srcPort = dot == std::string::npos ? "" : ref.substr(dot + 1);
                    int src = g.findNode(srcId);
                    if (dot == std::string::npos || srcId.empty() || srcPort.empty()) {
                        std::string sug;
                        if (src >= 0) sug = "@" + srcId + "." + g.nodes[src].spec->outputs.front().name;
                        else if (!nearestName(srcId, ids).empty()) sug = "@" + nearestName(srcId, ids) + ".<output>";
                        throw InputError(ip, "malformed reference '" + val.get<std::string>() + "': expected \"@node.output\"", sug);
                    }
                    if (src < 0) throw InputError(ip, "reference to unknown node '" + srcId + "'", nearestName(srcId, ids));
                    const NodeSpec& ss = *g.nodes[src].spec;
                    int sp = ss.outputIndex(srcPort);
                    if (sp < 0)
                        throw InputError(ip, "node '" + srcId + "' (" + ss.id + ") has no output '" + srcPort + "' (outputs: " + typeList(ss.outputNames()) + ")",
                                         nearestName(srcPort, ss.outputNames()));
                    TypeDesc st = ss.outputs[sp].type;
                    if (st != p.type) {
                        std::string conv = std::string("convert.") + typeName(st) + "_to_" + typeName(p.type);
                        if (!NodeRegistry::instance().find(conv)) conv.clear();
                        throw InputError(ip, std::string("wrong type: input '") + p.name + "' of " + spec.id + " is " + typeName(p.type) + " but '" +
                                                 val.get<std::string>() + "' is " + typeName(st) +
                                                 " (connections must match exactly; insert an explicit convert node)",
                                         conv);
                    }
                    v.kind = InputValue::Kind::Connection;
                    v.srcNode = src;
                    v.srcPort = sp;
                    continue;
                }
                if (p.type == TypeDesc::Closure)
                    throw InputError(ip, "input '" + p.name + "' of " + spec.id + " is a closure and must be connected (\"@node.output\")",
                                     suggestClosureSource(g, int(ni)));
                if (p.type == TypeDesc::String) {
                    if (!val.is_string()) throw InputError(ip, "wrong type: input '" + p.name + "' of " + spec.id + " is a string");
                    v.str = val.get<std::string>();
                    if (!p.enumValues.empty()) {
                        auto f = std::find(p.enumValues.begin(), p.enumValues.end(), v.str);
                        if (f == p.enumValues.end())
                            throw InputError(ip, "invalid value '" + v.str + "' for '" + p.name + "' (one of: " + typeList(p.enumValues) + ")",
                                             nearestName(v.str, p.enumValues));
                        v.enumIndex = int(f - p.enumValues.begin());
                    }
                    v.kind = InputValue::Kind::Literal;
                    continue;
                }
                if (!parseNumeric(val, p.type, v.value)) {
                    int w = typeWidth(p.type);
                    std::string want = w == 1 ? "a number" : "a number or an array of " + std::to_string(w) + " numbers";
                    std::string sug;
                    if (val.is_string()) sug = "@" + val.get<std::string>();
                    throw InputError(ip, std::string("wrong type: input '") + p.name + "' of " + spec.id + " is " + typeName(p.type) +
                                             ", expected " + want + " or \"@node.output\"",
                                     sug.size() > 1 && val.get<std::string>().find('.') != std::string::npos ? sug : "");
                }
                checkRange(p, spec, v.value, ip, g.warnings);
                v.kind = InputValue::Kind::Literal;
            }
        }
    }

    // Pass 3: required inputs.
    for (size_t ni = 0; ni < g.nodes.size(); ++ni) {
        NodeInstance& n = g.nodes[ni];
        for (size_t k = 0; k < n.spec->inputs.size(); ++k) {
            const PortSpec& p = n.spec->inputs[k];
            const InputValue& v = n.inputs[k];
            if (!p.required || v.kind == InputValue::Kind::Connection || v.kind == InputValue::Kind::Literal) continue;
            std::string sug;
            if (p.type == TypeDesc::Closure) sug = suggestClosureSource(g, int(ni));
            throw InputError(v.pointer, "required input '" + p.name + "' of " + n.spec->id + " (node '" + n.id + "') is not " +
                                            (p.type == TypeDesc::String ? "given" : "connected"),
                             sug);
        }
    }

    // Pass 4: topological order + cycle detection (DFS in id order: deterministic). Iterative, with an explicit stack
    // of (node, next input): a chain of ~29k nodes overflowed the call stack of the recursive form (issue 16).
    std::vector<int> state(g.nodes.size(), 0);  // 0 new, 1 on stack, 2 done
    std::vector<std::pair<int, size_t>> path;   // the DFS stack: node and the index of its next input to visit
    for (size_t root = 0; root < g.nodes.size(); ++root) {
        if (state[root] != 0) continue;
        state[root] = 1;
        path.push_back({int(root), 0});
        while (!path.empty()) {
            auto& [n, next] = path.back();
            const std::vector<InputValue>& inputs = g.nodes[n].inputs;
            if (next == inputs.size()) {
                state[n] = 2;
                g.order.push_back(n);
                path.pop_back();
                continue;
            }
            const InputValue& in = inputs[next++];
            if (in.kind != InputValue::Kind::Connection) continue;
            if (state[in.srcNode] == 1) {
                std::string cyc;
                auto it = std::find_if(path.begin(), path.end(), [&](const auto& e) { return e.first == in.srcNode; });
                for (; it != path.end(); ++it) cyc += g.nodes[it->first].id + " -> ";
                cyc += g.nodes[in.srcNode].id;
                throw InputError(in.pointer, "cycle in the node graph: " + cyc + " (a graph must be acyclic; remove this connection)",
                                 "");
            }
            if (state[in.srcNode] == 0) {
                state[in.srcNode] = 1;
                path.push_back({in.srcNode, 0});  // invalidates n/next: the loop re-reads path.back()
            }
        }
    }

    // Output.
    if (!mat.contains("output"))
        throw InputError(pointer, "material graph has no \"output\"", opt.requireClosureOutput ? suggestClosureSource(g, -1) : "output");
    const json& out = mat["output"];
    std::string op = pointer + "/output";
    if (!out.is_string() || out.get<std::string>().size() < 2 || out.get<std::string>()[0] != '@')
        throw InputError(op, "\"output\" must be a reference \"@node.output\"", suggestClosureSource(g, -1));
    std::string ref = out.get<std::string>().substr(1);
    size_t dot = ref.rfind('.');
    if (dot == std::string::npos) {
        int src = g.findNode(ref);
        throw InputError(op, "malformed reference '" + out.get<std::string>() + "': expected \"@node.output\"",
                         src >= 0 ? "@" + ref + "." + g.nodes[src].spec->outputs.front().name : nearestName(ref, ids));
    }
    g.outputNode = g.findNode(ref.substr(0, dot));
    if (g.outputNode < 0) throw InputError(op, "reference to unknown node '" + ref.substr(0, dot) + "'", nearestName(ref.substr(0, dot), ids));
    const NodeSpec& os = *g.nodes[g.outputNode].spec;
    g.outputPort = os.outputIndex(ref.substr(dot + 1));
    if (g.outputPort < 0)
        throw InputError(op, "node '" + ref.substr(0, dot) + "' (" + os.id + ") has no output '" + ref.substr(dot + 1) + "'",
                         nearestName(ref.substr(dot + 1), os.outputNames()));
    if (opt.requireClosureOutput && os.outputs[g.outputPort].type != TypeDesc::Closure)
        throw InputError(op, "material output must be a closure, but '" + out.get<std::string>() + "' is " +
                                 typeName(os.outputs[g.outputPort].type),
                         suggestClosureSource(g, -1));
    return g;
}

// ---- compilation ---------------------------------------------------------------------------------

namespace {
// Registers of a shade() on the stack; larger programs take their registers from the arena (run).
constexpr size_t kShadeStackRegisters = 256;

// Where loadBinding(b) copies its value from: the byte offset of that field of ShadingPoint, or -1 for a binding it
// computes (NdotV, the pixel footprints, frontFacing). ParamRead::ShadingPointBytes copies the same floats.
int shadingPointOffset(GeomBinding b) {
    static const ShadingPoint probe;
    auto at = [](const void* member) {
        return int(reinterpret_cast<const char*>(member) - reinterpret_cast<const char*>(&probe));
    };
    switch (b) {
        case GeomBinding::UV: return at(&probe.uv);
        case GeomBinding::DUVDX: return at(&probe.duvdx);
        case GeomBinding::DUVDY: return at(&probe.duvdy);
        case GeomBinding::P: return at(&probe.p);
        case GeomBinding::N: return at(&probe.n);
        case GeomBinding::Ng: return at(&probe.ng);
        case GeomBinding::T: return at(&probe.tangent);  // its xyz
        case GeomBinding::TSign: return at(&probe.tangent.w);
        case GeomBinding::DNDX: return at(&probe.dndx);
        case GeomBinding::DNDY: return at(&probe.dndy);
        default: return -1;
    }
}
// Whether NodeParams::read can take port k of a node fed by its binding from the shading point itself: a numeric
// member of the parameter struct, declared with that binding and as wide as it (Instr::boundPorts).
bool readsBindingDirectly(const NodeSpec& spec, size_t k) {
    if (!spec.params) return false;
    for (const ParamField& f : spec.params->fields)
        if (f.port == k)
            return f.kind == ParamField::Floats && f.binding == spec.inputs[k].binding &&
                   f.width == typeWidth(bindingType(f.binding));
    return false;
}
}  // namespace

Program Program::compile(const GraphDesc& g, const std::vector<std::pair<int, int>>& roots, const GraphLoadContext* load) {
    Program prog;
    std::vector<int> live = g.liveOrder(roots);
    std::vector<std::vector<uint16_t>> outRegs(g.nodes.size());
    std::vector<char> constNode(g.nodes.size(), 0);
    std::map<GeomBinding, uint16_t> bindingRegs;
    std::vector<GeomBinding> bindingOrder;  // in order of first use: the prologue's order
    std::set<GeomBinding> loadedBindings;   // bindings some instruction reads through its register
    auto alloc = [&](int w) {
        // Instr holds 16-bit register indices: a graph that needs more registers is refused here rather than shaded
        // with wrapped indices (a 14-level tree of closure.add printed f = 0 where 0.159 is right; issue 16).
        if (prog.tmpl_.size() + size_t(w) > kMaxRegisters)
            throw InputError(g.pointer, "the graph needs more than " + std::to_string(kMaxRegisters) + " registers (" +
                                            std::to_string(live.size()) + " live nodes); split it into smaller materials");
        uint16_t r = uint16_t(prog.tmpl_.size());
        for (int i = 0; i < w; ++i) prog.tmpl_.push_back(0.f);
        return r;
    };
    std::vector<std::pair<int, uint16_t>> closureOuts;  // (node, register) of kept closure outputs

    // Outputs read by a live node or named as roots (Instr::usedOutputs).
    std::vector<uint8_t> usedOut(g.nodes.size(), 0);
    for (int ni : live)
        for (const InputValue& v : g.nodes[ni].inputs)
            if (v.kind == InputValue::Kind::Connection) usedOut[v.srcNode] |= uint8_t(1u << v.srcPort);
    for (auto& r : roots) usedOut[r.first] |= uint8_t(1u << r.second);
    for (int ni : live) {
        const NodeInstance& n = g.nodes[ni];
        const NodeSpec& spec = *n.spec;
        Instr ins;
        ins.usedOutputs = usedOut[ni];
        std::fill(std::begin(ins.in), std::end(ins.in), kNoRegister);
        std::fill(std::begin(ins.out), std::end(ins.out), kNoRegister);
        ins.fn = load && load->gpuSubstitutes && spec.gpuSubstituteCpu ? spec.gpuSubstituteCpu : spec.cpu;
        ins.batchFn = ins.fn == spec.cpu ? spec.cpuBatch : nullptr;
        bool allConst = true;
        uint32_t dynamicPorts = 0;  // inputs that vary per shading point: bindings and outputs of unfolded nodes
        std::vector<std::string> strings(spec.inputs.size());
        for (size_t k = 0; k < spec.inputs.size(); ++k) {
            const PortSpec& p = spec.inputs[k];
            const InputValue& v = n.inputs[k];
            if (p.type == TypeDesc::String) {
                strings[k] = v.str;
                if (!p.enumValues.empty()) ins.in[k] = uint16_t(std::max(v.enumIndex, 0));
                continue;
            }
            switch (v.kind) {
                case InputValue::Kind::Connection:
                    ins.in[k] = outRegs[v.srcNode][v.srcPort];
                    if (!constNode[v.srcNode]) allConst = false, dynamicPorts |= 1u << k;
                    break;
                case InputValue::Kind::Binding: {
                    if (isDerivativeBinding(p.binding)) prog.needsDerivatives_ = true;
                    auto it = bindingRegs.find(p.binding);
                    if (it == bindingRegs.end()) {
                        uint16_t r = alloc(typeWidth(bindingType(p.binding)));
                        it = bindingRegs.emplace(p.binding, r).first;
                        bindingOrder.push_back(p.binding);
                    }
                    ins.in[k] = it->second;
                    allConst = false;
                    dynamicPorts |= 1u << k;
                    // A member of the node's parameter struct of the binding's width is read from the shading point
                    // directly (Instr::boundPorts); anything else reads the register, which the prologue then fills.
                    if (readsBindingDirectly(spec, k))
                        ins.boundPorts |= 1u << k;
                    else
                        loadedBindings.insert(p.binding);
                    break;
                }
                case InputValue::Kind::Literal:
                case InputValue::Kind::Default: {
                    int w = typeWidth(p.type);
                    uint16_t r = alloc(w);
                    for (int c = 0; c < w; ++c) prog.tmpl_[r + c] = v.value[c];
                    ins.in[k] = r;
                    break;
                }
            }
        }
        bool closureOut = false;
        for (size_t k = 0; k < spec.outputs.size(); ++k) {
            ins.out[k] = alloc(typeWidth(spec.outputs[k].type));
            outRegs[ni].push_back(ins.out[k]);
            if (spec.outputs[k].type == TypeDesc::Closure) closureOut = true;
        }
        if (spec.has(kPure) && allConst && !closureOut && !spec.prepare) {
            // Constant folding: run the node once now; its outputs become template constants.
            EvalContext ctx;
            ctx.r = prog.tmpl_.data();
            ctx.constants = prog.tmpl_.data();
            spec.cpu(ctx, ins);
            constNode[ni] = 1;
            ++prog.folded_;
            continue;
        }
        if (spec.prepare) {
            PrepareContext pc;
            pc.spec = &spec;
            pc.strings = &strings;
            pc.load = load;
            std::vector<std::array<float, 3>> values;
            for (auto& v : n.inputs) pc.pointers.push_back(v.pointer), values.push_back(v.value);
            pc.values = &values;
            auto d = spec.prepare(pc);
            ins.data = d.get();
            prog.data_.push_back(std::move(d));
        }
        for (size_t k = 0; k < spec.outputs.size(); ++k)
            if (spec.outputs[k].type == TypeDesc::Closure) {
                prog.tmpl_[ins.out[k]] = float(prog.slots_);
                closureOuts.push_back({ni, ins.out[k]});
                ++prog.slots_;
            }
        if (spec.has(kEmissive)) prog.emissive_ = true;
        if (spec.has(kNeedsDerivatives)) prog.needsDerivatives_ = true;
        if (spec.params) prog.preRead(ins, *spec.params, dynamicPorts);
        // A shade may skip copying the register template when no instruction reads a register it did not write:
        // every port of every node pre-read or taken from the shading point (closure pool indices are read from the
        // template itself, slotOf). Nodes without a parameter struct read their registers directly.
        if (!ins.constLayout || (ins.dynamicPorts & ~ins.boundPorts) != 0) prog.readsTemplate_ = true;
        prog.code_.push_back(ins);
    }
    for (GeomBinding b : bindingOrder)
        if (loadedBindings.count(b)) prog.prologue_.push_back({b, bindingRegs[b]});
    for (auto& r : roots) prog.rootRegs_.push_back(outRegs[r.first][r.second]);
    if (!roots.empty() && g.nodes[roots[0].first].spec->outputs[roots[0].second].type == TypeDesc::Closure)
        prog.outSlot_ = int(prog.tmpl_[prog.rootRegs_[0]]);
    prog.singleClosureNode_ = prog.code_.size() == 1 && prog.slots_ == 1 && prog.outSlot_ == 0 && prog.prologue_.empty() &&
                              !prog.readsTemplate_ && prog.tmpl_.size() <= kShadeStackRegisters;
    return prog;
}

void Program::preRead(Instr& ins, const ParamLayout& layout, uint32_t dynamicPorts) {
    // The block is read with the register template: constants, literals and folded outputs are final there; the
    // closure ports (a pool index, fixed per program) are read per shade all the same.
    // max_align_t storage: NodeParams refuses parameter structs aligned beyond it.
    const size_t words = (layout.size + sizeof(std::max_align_t) - 1) / sizeof(std::max_align_t);
    std::shared_ptr<std::max_align_t[]> storage(new std::max_align_t[words]());
    std::shared_ptr<char> block(storage, reinterpret_cast<char*>(storage.get()));
    for (const ParamField& f : layout.fields) {
        // A closure port holds a pool index, fixed per program: constant like a literal.
        if (f.kind == ParamField::Closure) dynamicPorts &= ~(1u << f.port);
        if (!(dynamicPorts >> f.port & 1)) readParamField(tmpl_.data(), ins, f, block.get());
    }
    ins.constParams = block.get();
    ins.constLayout = &layout;
    ins.dynamicPorts = dynamicPorts;
    data_.push_back(std::shared_ptr<const void>(block, block.get()));
    // The reads of the ports that vary (Instr::reads), in port order.
    std::vector<ParamRead> reads;
    for (const ParamField& f : layout.fields) {
        if (!(dynamicPorts >> f.port & 1)) continue;
        ParamRead rd{f.offset, ins.in[f.port], f.width, ParamRead::Register, GeomBinding::None};
        if (ins.boundPorts >> f.port & 1) {
            const int at = shadingPointOffset(f.binding);
            if (at >= 0) {
                rd.from = ParamRead::ShadingPointBytes;
                rd.source = uint16_t(at);
            } else {
                rd.from = ParamRead::Binding;
                rd.binding = f.binding;
            }
        }
        reads.push_back(rd);
    }
    if (!reads.empty()) {
        std::shared_ptr<ParamRead[]> stored(new ParamRead[reads.size()]);
        std::copy(reads.begin(), reads.end(), stored.get());
        ins.reads = stored.get();
        ins.readCount = uint8_t(reads.size());
        data_.push_back(std::shared_ptr<const void>(stored, stored.get()));
    }
}

namespace {
// The context a shade's instructions see: registers r (constants: the program's template), closures cl, emission em.
inline EvalContext evalContext(const ShadingPoint& sp, ScratchArena& arena, float* r, const float* constants,
                               Closure** cl, Color3* em) {
    EvalContext ctx;
    ctx.r = r;
    ctx.constants = constants;
    ctx.sp = &sp;
    ctx.arena = &arena;
    ctx.closures = cl;
    ctx.emission = em;
    return ctx;
}
}  // namespace

// Inlined into execute and shadeBatch: a shade is a few dozen instructions of set-up around the nodes, and a call
// here saved and restored six registers and copied the context out (callgrind, bench_graph: 63 of ~490 instructions).
__attribute__((always_inline)) inline EvalContext Program::prepare(const ShadingPoint& sp, ScratchArena& arena, float* r, Closure** cl, Color3* em, Closure* out,
                             bool wholeRegisterFile) const {
    if (wholeRegisterFile || readsTemplate_) std::memcpy(r, tmpl_.data(), tmpl_.size() * sizeof(float));
    for (size_t s = 0; s < slots_; ++s) {
        em[s] = Color3(0.f);
        if (out && int(s) == outSlot_)
            cl[s] = out;
        else
            cl[s] = new (arena.allocate(sizeof(Closure), alignof(Closure))) Closure();
    }
    for (const Load& l : prologue_) loadBinding(l.binding, sp, r + l.reg);
    return evalContext(sp, arena, r, tmpl_.data(), cl, em);
}

__attribute__((always_inline)) inline void Program::execute(const ShadingPoint& sp, ScratchArena& arena, float* r, Closure** cl, Color3* em, Closure* out,
                      Color3* emission, bool wholeRegisterFile) const {
    EvalContext ctx = prepare(sp, arena, r, cl, em, out, wholeRegisterFile);
    for (const Instr& ins : code_) ins.fn(ctx, ins);
    if (emission) *emission = outSlot_ >= 0 ? em[outSlot_] : Color3(0.f);
}

const float* Program::run(const ShadingPoint& sp, ScratchArena& arena, Closure* out, Color3* emission) const {
    float* r = static_cast<float*>(arena.allocate(tmpl_.size() * sizeof(float) + 4, 16));
    size_t n = std::max<size_t>(slots_, 1);
    auto** cl = static_cast<Closure**>(arena.allocate(n * sizeof(Closure*), alignof(Closure*)));
    auto* em = static_cast<Color3*>(arena.allocate(n * sizeof(Color3), alignof(Color3)));
    execute(sp, arena, r, cl, em, out, emission, true);
    return r;
}

void Program::shade(const ShadingPoint& sp, ScratchArena& arena, Closure* out, Color3* emission) const {
    constexpr size_t kStackRegs = kShadeStackRegisters, kStackSlots = 16;
    if (singleClosureNode_ && out) {
        // What execute does for this program, its loops unrolled: the one closure is 'out', the one node runs.
        alignas(16) float r[kStackRegs];
        Closure* cl[1] = {out};
        Color3 em[1] = {Color3(0.f)};
        EvalContext ctx = evalContext(sp, arena, r, tmpl_.data(), cl, em);
        const Instr& ins = code_.front();
        ins.fn(ctx, ins);
        if (emission) *emission = em[0];
        return;
    }
    if (tmpl_.size() > kStackRegs || slots_ > kStackSlots) {
        run(sp, arena, out, emission);
        return;
    }
    alignas(16) float r[kStackRegs];
    Closure* cl[kStackSlots];
    Color3 em[kStackSlots];
    execute(sp, arena, r, cl, em, out, emission, false);
}

void Program::shadeBatch(const ShadingPoint* const* sps, size_t n, ScratchArena& arena, Closure* const* out,
                         Color3* emission) const {
    // Registers, closure pools and contexts of a sub-batch live on the stack; a program too large for a useful
    // sub-batch is shaded point by point.
    constexpr size_t kStackFloats = 4096, kStackSlots = 512, kMaxBatch = 64;
    const size_t regs = std::max<size_t>(tmpl_.size(), 1), slots = std::max<size_t>(slots_, 1);
    const size_t sub = std::min({kMaxBatch, kStackFloats / regs, kStackSlots / slots});
    if (sub < 4) {
        for (size_t k = 0; k < n; ++k) shade(*sps[k], arena, out[k], emission ? &emission[k] : nullptr);
        return;
    }
    alignas(16) float r[kStackFloats];
    Closure* cl[kStackSlots];
    Color3 em[kStackSlots];
    EvalContext ctx[kMaxBatch];
    for (size_t begin = 0; begin < n; begin += sub) {
        const size_t m = std::min(sub, n - begin);
        if (singleClosureNode_) {
            // prepare() for this program: the one closure is out[k], nothing to load (see shade).
            for (size_t k = 0; k < m; ++k) {
                cl[k] = out[begin + k];
                em[k] = Color3(0.f);
                ctx[k] = evalContext(*sps[begin + k], arena, r + k * regs, tmpl_.data(), cl + k, em + k);
            }
        } else {
            for (size_t k = 0; k < m; ++k)  // execute()'s prologue, point by point
                ctx[k] = prepare(*sps[begin + k], arena, r + k * regs, cl + k * slots, em + k * slots, out[begin + k], false);
        }
        for (const Instr& ins : code_) {
            if (ins.batchFn) {
                ins.batchFn(ctx, m, ins);
            } else {
                for (size_t k = 0; k < m; ++k) ins.fn(ctx[k], ins);
            }
        }
        if (emission)
            for (size_t k = 0; k < m; ++k) emission[begin + k] = outSlot_ >= 0 ? em[k * slots + size_t(outSlot_)] : Color3(0.f);
    }
}

}  // namespace specula::graph
