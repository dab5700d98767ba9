// GlslEmitter: graph -> readable GLSL 4.50 (named variables per node output, node ids in comments).
#include "core/codegen/glsl_emitter.h"

#include "core/codegen/glsl_signature.h"
#include "core/codegen/glsl_sources.h"

#include <algorithm>
#include <cctype>
#include <stdexcept>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>

namespace specula::codegen {

using namespace specula::graph;

std::string glslFloat(float v) {
    if (std::isnan(v)) return "(0.0/0.0)";
    if (std::isinf(v)) return v > 0 ? "(1.0/0.0)" : "(-1.0/0.0)";
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.9g", v);
    std::string s = buf;
    if (s.find_first_of(".e") == std::string::npos) s += ".0";
    return s;
}

std::string glslLiteral(TypeDesc t, const std::array<float, 3>& v) {
    switch (typeWidth(t)) {
        case 1: return glslFloat(v[0]);
        case 2: return "vec2(" + glslFloat(v[0]) + ", " + glslFloat(v[1]) + ")";
        default: return "vec3(" + glslFloat(v[0]) + ", " + glslFloat(v[1]) + ", " + glslFloat(v[2]) + ")";
    }
}

std::string glslIdentifier(const std::string& s) {
    std::string r;
    for (char c : s) r += (std::isalnum((unsigned char)c) ? c : '_');
    if (r.empty() || std::isdigit((unsigned char)r[0])) r = "n_" + r;
    // GLSL reserves identifiers containing "__" and the gl_ prefix.
    while (r.find("__") != std::string::npos) r.replace(r.find("__"), 2, "_");
    if (r.rfind("gl_", 0) == 0) r = "n_" + r;
    return r;
}

std::string glslCommentText(const std::string& s) {
    // Names come from the scene file: a newline would end the comment and inject source, a trailing backslash would
    // splice the next line into it, and bytes outside printable ASCII may not be valid UTF-8 (issue 16).
    std::string r;
    for (char c : s) r += (c >= 0x20 && c <= 0x7e && c != '\\') ? c : '?';
    return r;
}

namespace {

std::string layoutPrefix(int set, int binding) {
    return "layout(" + (set >= 0 ? "set = " + std::to_string(set) + ", " : std::string()) + "binding = " + std::to_string(binding);
}

}  // namespace

GlslModule emitGlsl(const GraphDesc& g, const GlslOptions& opt) {
    GlslModule mod;
    std::vector<int> live = g.liveOrder({{g.outputNode, g.outputPort}});
    const std::string px = opt.prefix.empty() ? "" : glslIdentifier(opt.prefix) + "_";
    mod.entryPrefix = "specula_" + px;

    // Unique variable stems per node.
    std::map<int, std::string> stem;
    std::set<std::string> used;
    for (int n : live) {
        std::string s = glslIdentifier(g.nodes[n].id);
        std::string u = s;
        for (int k = 2; used.count(u); ++k) u = s + "_" + std::to_string(k);
        used.insert(u);
        stem[n] = u;
    }

    // Every node's function bound to its ports by name (throws on a mismatch: a programming error of the node).
    std::map<int, GlslNodeBinding> binding;
    for (int n : live) binding[n] = bindGlslFunction(*g.nodes[n].spec);

    // Uniforms (std140) and resources.
    mod.uniformBinding = opt.bindingBase;
    mod.uniformSet = opt.set;
    uint32_t offset = 0;
    std::map<std::pair<int, int>, std::string> uniformOf, resourceOf;
    int nextBinding = opt.bindingBase + 1;
    // Built-in tables hold the same texels for every node instance (the LTC fits, the glint dictionary): one uniform
    // per table and module, shared by all its users (a diffuse + GGX mix binds the LTC amplitude table once), which
    // keeps modules within the sampler limits. Keyed by the texel producer and the GLSL type.
    std::vector<std::pair<std::pair<ResourceImage (*)(const void*), std::string>, std::string>> sharedTables;
    for (int n : live) {
        const NodeInstance& ni = g.nodes[n];
        for (size_t r = 0; r < ni.spec->resources.size(); ++r) {
            const ResourceSpec& rs = ni.spec->resources[r];
            const bool shared = rs.kind == ResourceSpec::Kind::BuiltinTable && rs.produce;
            if (shared) {
                auto it = std::find_if(sharedTables.begin(), sharedTables.end(), [&](const auto& e) {
                    return e.first.first == rs.produce && e.first.second == rs.glslType;
                });
                if (it != sharedTables.end()) {
                    resourceOf[{n, int(r)}] = it->second;
                    continue;
                }
            }
            GlslResource res;
            // Shared tables are named by the resource ("table_" cannot clash with a node stem's "res_" names).
            res.name = shared ? "spc_" + px + "table_" + glslIdentifier(rs.name) : "spc_" + px + "res_" + stem[n] + "_" + rs.name;
            if (shared) {
                for (int k = 2; std::any_of(sharedTables.begin(), sharedTables.end(), [&](const auto& e) { return e.second == res.name; }); ++k)
                    res.name = "spc_" + px + "table_" + glslIdentifier(rs.name) + "_" + std::to_string(k);
                sharedTables.push_back({{rs.produce, rs.glslType}, res.name});
            }
            res.glslType = rs.glslType;
            res.binding = nextBinding++;
            res.set = opt.set;
            res.nodeId = ni.id;
            res.nodeType = ni.spec->id;
            res.resource = rs.name;
            res.kind = rs.kind;
            if (rs.kind != ResourceSpec::Kind::BuiltinTable) {
                int f = rs.fileInput.empty() ? -1 : ni.spec->inputIndex(rs.fileInput);
                int c = rs.colorspaceInput.empty() ? -1 : ni.spec->inputIndex(rs.colorspaceInput);
                if (f >= 0) res.file = ni.inputs[f].str;
                res.colorspace = c >= 0 ? ni.inputs[c].str : "raw";
            }
            resourceOf[{n, int(r)}] = res.name;
            mod.resources.push_back(res);
        }
        if (!opt.literalsAsUniforms) continue;
        for (size_t k = 0; k < ni.spec->inputs.size(); ++k) {
            const PortSpec& p = ni.spec->inputs[k];
            if (!isNumeric(p.type) || ni.inputs[k].kind != InputValue::Kind::Literal) continue;
            uint32_t align = typeWidth(p.type) == 1 ? 4 : typeWidth(p.type) == 2 ? 8 : 16;
            offset = (offset + align - 1) / align * align;
            GlslUniform u;
            u.name = "u_" + px + stem[n] + "_" + p.name;
            u.type = p.type;
            u.offset = offset;
            u.value = ni.inputs[k].value;
            u.pointer = ni.inputs[k].pointer;
            offset += 4 * typeWidth(p.type);
            uniformOf[{n, int(k)}] = u.name;
            mod.uniforms.push_back(u);
        }
    }
    mod.uniformBlockSize = (offset + 15) / 16 * 16;

    // Used node functions: one copy per .glsl file, sorted by file path (stable).
    std::map<std::string, std::set<std::string>> files;
    for (int n : live) files[g.nodes[n].spec->glslFile].insert(g.nodes[n].spec->id);
    std::set<std::string> types;
    for (int n : live) types.insert(g.nodes[n].spec->id);
    mod.nodeTypes.assign(types.begin(), types.end());
    for (const std::string& t : mod.nodeTypes) {
        const NodeSpec* spec = NodeRegistry::instance().find(t);
        if (spec && !spec->gpuSubstitute.empty())
            mod.warnings.push_back(t + ": not supported on the GPU; the GLSL substitutes " + spec->gpuSubstitute);
    }

    const std::string E = mod.entryPrefix;
    std::ostringstream o;
    o << "#version 450\n";
    o << "// Generated by Specula " << "from material '" << glslCommentText(opt.materialName) << "' (" << glslCommentText(g.pointer) << "). Do not edit.\n";
    o << "// Entry points: vec3 " << E << "eval(SpeculaShadingInputs s, vec3 wo, vec3 wi) returns f·cos for one light\n";
    o << "// direction (wo, wi: unit, world space, pointing away from the surface); " << E << "emission(s, wo);\n";
    o << "// " << E << "material(SpeculaClosureQuery q, SpeculaShadingInputs s, out SpeculaClosure c) answers any query.\n";
    o << "// Bind the uniform block and every resource listed in the module's manifest (specula glsl --resources).\n";
    for (const std::string& w : mod.warnings) o << "// WARNING: " << glslCommentText(w) << "\n";
    o << "\n";
    o << glslPrelude() << "\n";
    // Enum constants of the live nodes (guarded: shared between nodes and modules).
    {
        std::set<std::string> seen;
        std::string enums;
        for (int n : live) {
            std::string c = glslEnumConstants(*g.nodes[n].spec);
            if (!c.empty() && seen.insert(c).second) enums += c;
        }
        if (!enums.empty()) o << "// ---- enum constants -----------------------------------------------------------------------\n" << enums << "\n";
    }
    if (!mod.uniforms.empty()) {
        o << "// ---- material parameters (std140; upload the values listed here) --------------------------\n";
        o << layoutPrefix(opt.set, mod.uniformBinding) << ", std140) uniform SpeculaMaterialParams" << (px.empty() ? "" : "_" + px.substr(0, px.size() - 1)) << " {\n";
        for (auto& u : mod.uniforms)
            o << "    " << glslTypeName(u.type) << " " << u.name << ";  // offset " << u.offset << ", "
              << glslCommentText(u.pointer) << " = " << glslLiteral(u.type, u.value) << "\n";
        o << "};\n\n";
    }
    for (auto& r : mod.resources) {
        o << layoutPrefix(r.set, r.binding) << ") uniform " << r.glslType << " " << r.name << ";  // ";
        if (r.kind == ResourceSpec::Kind::BuiltinTable)
            o << "built-in table '" << r.resource << "', shared by every node reading it (first: '" << glslCommentText(r.nodeId) << "' ("
              << r.nodeType << "))\n";
        else
            o << "node '" << glslCommentText(r.nodeId) << "' (" << r.nodeType << ") resource '" << r.resource << "' ("
              << resourceKindName(r.kind) << ")"
              << (r.file.empty() ? "" : ": \"" + glslCommentText(r.file) + "\", colorspace " + glslCommentText(r.colorspace))
              << "\n";
    }
    if (!mod.resources.empty()) o << "\n";
    // Shared libraries of the live nodes (NodeSpec::glslLibraries), each once, in first-use order over the sorted
    // node files, before any node file calls into them (guarded too: modules may be concatenated).
    std::set<std::string> emittedLibraries;
    for (auto& fileIds : files)
        for (int n : live)
            if (g.nodes[n].spec->glslFile == fileIds.first)
                for (const std::string& lib : g.nodes[n].spec->glslLibraries)
                    if (emittedLibraries.insert(lib).second) o << glslLibraryText(lib) << "\n";
    for (auto& [file, ids] : files) {
        std::string list;
        for (auto& id : ids) list += (list.empty() ? "" : ", ") + id;
        // A node file another node already uses as a library is in the module once, above (same guard).
        if (emittedLibraries.count(file)) {
            o << "// ---- nodes/" << file << " (" << list << "): emitted above as a library\n\n";
            continue;
        }
        const std::string guard = glslFileGuard(file);
        o << "// ---- nodes/" << file << " (" << list << ")\n#ifndef " << guard << "\n#define " << guard << "\n";
        const std::string* src = codegen::embeddedGlsl(file);
        o << (src ? *src : std::string("#error missing node source ") + file + "\n") << "#endif\n\n";
    }

    // The graph body.
    auto var = [&](int n, int port) { return stem[n] + "_" + g.nodes[n].spec->outputs[port].name; };
    o << "// ---- the graph ------------------------------------------------------------------------------\n";
    o << "void " << E << "material(SpeculaClosureQuery q, SpeculaShadingInputs s, out SpeculaClosure result) {\n";
    for (int n : live) {
        const NodeInstance& ni = g.nodes[n];
        const NodeSpec& sp = *ni.spec;
        o << "    // node '" << glslCommentText(ni.id) << "' (" << sp.id << ")\n";
        for (size_t k = 0; k < sp.outputs.size(); ++k)
            o << "    " << glslTypeName(sp.outputs[k].type) << " " << var(n, int(k)) << ";\n";
        std::vector<std::string> args;
        for (const GlslArgRole& role : binding[n].roles) {
            switch (role.kind) {
                case GlslArgRole::Query: args.push_back("q"); break;
                case GlslArgRole::Shading: args.push_back("s"); break;
                case GlslArgRole::Resource: args.push_back(resourceOf[{n, role.index}]); break;
                case GlslArgRole::Output: args.push_back(var(n, role.index)); break;
                case GlslArgRole::Input: {
                    const int k = role.index;
                    const PortSpec& p = sp.inputs[k];
                    const InputValue& v = ni.inputs[k];
                    if (p.type == TypeDesc::String) {
                        int idx = std::max(v.enumIndex, 0);
                        args.push_back(glslEnumConstant(p, idx) + " /* " + p.name + " = " + v.str + " */");
                        break;
                    }
                    switch (v.kind) {
                        case InputValue::Kind::Connection: args.push_back(var(v.srcNode, v.srcPort)); break;
                        case InputValue::Kind::Binding: args.push_back(bindingGlsl(p.binding)); break;
                        case InputValue::Kind::Literal:
                            if (uniformOf.count({n, k})) {
                                args.push_back(uniformOf[{n, k}]);
                                break;
                            }
                            [[fallthrough]];
                        case InputValue::Kind::Default: args.push_back(glslLiteral(p.type, v.value)); break;
                    }
                    break;
                }
            }
        }
        o << "    " << sp.glslFunction << "(";
        for (size_t a = 0; a < args.size(); ++a) o << (a ? ", " : "") << args[a];
        o << ");\n";
    }
    o << "    result = " << var(g.outputNode, g.outputPort) << ";\n}\n\n";
    o << "vec3 " << E << "eval(SpeculaShadingInputs s, vec3 wo, vec3 wi) {\n"
         "    SpeculaClosure c;\n    " << E << "material(specula_direction_query(wo, wi, 1.0 / 0.0), s, c);\n    return c.f;\n}\n\n";
    o << "vec3 " << E << "emission(SpeculaShadingInputs s, vec3 wo) {\n"
         "    SpeculaClosure c;\n    " << E << "material(specula_direction_query(wo, wo, 1.0 / 0.0), s, c);\n    return c.emission;\n}\n";
    mod.source = o.str();
    return mod;
}

std::vector<ResourceImage> nodeResourceImages(const NodeSpec& spec, const std::vector<std::string>& strings,
                                              const std::vector<std::string>& pointers, const GraphLoadContext& load,
                                              const std::vector<std::array<float, 3>>* values) {
    std::shared_ptr<const void> prepared;
    if (spec.prepare) {
        PrepareContext pc;
        pc.spec = &spec;
        pc.strings = &strings;
        pc.load = &load;
        pc.pointers = pointers;
        pc.values = values;
        prepared = spec.prepare(pc);
    }
    std::vector<ResourceImage> out;
    for (const ResourceSpec& rs : spec.resources) {
        if (!rs.produce) throw std::runtime_error(spec.id + ": resource '" + rs.name + "' has no texels to export");
        out.push_back(rs.produce(prepared.get()));
    }
    return out;
}

std::vector<ResourceImage> exportGlslResources(const GraphDesc& g, const GlslModule& mod, const GraphLoadContext& load) {
    std::vector<ResourceImage> out;
    std::map<int, std::vector<ResourceImage>> perNode;
    for (const GlslResource& r : mod.resources) {
        int n = g.findNode(r.nodeId);
        const NodeInstance& ni = g.nodes[size_t(n)];
        if (!perNode.count(n)) {
            std::vector<std::string> strings, pointers;
            std::vector<std::array<float, 3>> values;
            for (const InputValue& v : ni.inputs) strings.push_back(v.str), pointers.push_back(v.pointer), values.push_back(v.value);
            perNode[n] = nodeResourceImages(*ni.spec, strings, pointers, load, &values);
        }
        for (size_t k = 0; k < ni.spec->resources.size(); ++k)
            if (ni.spec->resources[k].name == r.resource) out.push_back(perNode[n][k]);
    }
    return out;
}

}  // namespace specula::codegen
