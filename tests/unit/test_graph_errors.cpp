// Graph input errors: each kind names the JSON pointer of the offending value and a suggestion.
#include "core/graph/graph_material.h"
#include "core/util/error.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

using namespace specula;
using nlohmann::json;

namespace {

// Loads 'm' as /materials/steel and returns the InputError (fails the test if none is thrown).
InputError loadError(const json& m) {
    try {
        loadGraphMaterial(m, "/materials/steel", GraphLoadContext{});
    } catch (const InputError& e) {
        return e;
    }
    ADD_FAILURE() << "no InputError for " << m.dump();
    return InputError("", "");
}

json ggx(json inputs) { return {{"type", "bsdf.ggx"}, {"inputs", inputs}}; }

}  // namespace

TEST(GraphErrors, UnknownNodeType) {
    InputError e = loadError({{"nodes", {{"spec", {{"type", "bsdf.gxx"}}}}}, {"output", "@spec.bsdf"}});
    EXPECT_EQ(e.pointer(), "/materials/steel/nodes/spec/type");
    EXPECT_EQ(e.suggestion(), "bsdf.ggx");
    EXPECT_NE(std::string(e.what()).find("/materials/steel/nodes/spec/type"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("did you mean 'bsdf.ggx'"), std::string::npos);
    // family name without the type suffix suggests a typed variant
    InputError e2 = loadError({{"nodes", {{"a", {{"type", "math.add"}}}, {"g", ggx(json::object())}}}, {"output", "@g.bsdf"}});
    EXPECT_EQ(e2.suggestion().rfind("math.add.", 0), 0u);
}

TEST(GraphErrors, UnknownPort) {
    InputError e = loadError({{"nodes", {{"spec", ggx({{"roughnes", 0.2}})}}}, {"output", "@spec.bsdf"}});
    EXPECT_EQ(e.pointer(), "/materials/steel/nodes/spec/inputs/roughnes");
    EXPECT_EQ(e.suggestion(), "roughness");
    EXPECT_NE(std::string(e.what()).find("did you mean 'roughness'"), std::string::npos);
    // unknown output port in a reference
    InputError e2 = loadError({{"nodes", {{"nm", {{"type", "texture.normal_map"}}}, {"spec", ggx({{"normal", "@nm.normals"}})}}},
                               {"output", "@spec.bsdf"}});
    EXPECT_EQ(e2.pointer(), "/materials/steel/nodes/spec/inputs/normal");
    EXPECT_EQ(e2.suggestion(), "normal");
}

TEST(GraphErrors, WrongType) {
    // connection type mismatch: colour into a float port, the suggestion is the explicit converter
    json nodes = {{"c", {{"type", "constant.color3"}, {"inputs", {{"value", {0.1, 0.2, 0.3}}}}}},
                  {"spec", ggx({{"roughness", "@c.out"}})}};
    InputError e = loadError({{"nodes", nodes}, {"output", "@spec.bsdf"}});
    EXPECT_EQ(e.pointer(), "/materials/steel/nodes/spec/inputs/roughness");
    EXPECT_EQ(e.suggestion(), "convert.color3_to_float");
    EXPECT_NE(std::string(e.what()).find("wrong type"), std::string::npos);
    // literal of the wrong shape
    InputError e2 = loadError({{"nodes", {{"spec", ggx({{"f0", {0.1, 0.2}}})}}}, {"output", "@spec.bsdf"}});
    EXPECT_EQ(e2.pointer(), "/materials/steel/nodes/spec/inputs/f0");
    // bad enum value gets the nearest choice
    InputError e3 = loadError({{"nodes", {{"spec", ggx({{"fresnel", "conductr"}})}}}, {"output", "@spec.bsdf"}});
    EXPECT_EQ(e3.pointer(), "/materials/steel/nodes/spec/inputs/fresnel");
    EXPECT_EQ(e3.suggestion(), "conductor");
}

TEST(GraphErrors, Cycle) {
    json nodes = {{"a", {{"type", "math.add.float"}, {"inputs", {{"a", "@b.out"}}}}},
                  {"b", {{"type", "math.mul.float"}, {"inputs", {{"a", "@a.out"}}}}},
                  {"spec", ggx({{"roughness", "@b.out"}})}};
    InputError e = loadError({{"nodes", nodes}, {"output", "@spec.bsdf"}});
    EXPECT_EQ(e.pointer(), "/materials/steel/nodes/b/inputs/a");
    EXPECT_NE(std::string(e.what()).find("cycle"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("a -> b -> a"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("remove this connection"), std::string::npos);
}

TEST(GraphErrors, UnconnectedRequiredInput) {
    json nodes = {{"d", {{"type", "bsdf.diffuse"}}}, {"spec", ggx(json::object())},
                  {"sum", {{"type", "closure.add"}, {"inputs", {{"a", "@spec.bsdf"}}}}}};
    InputError e = loadError({{"nodes", nodes}, {"output", "@sum.bsdf"}});
    EXPECT_EQ(e.pointer(), "/materials/steel/nodes/sum/inputs/b");
    EXPECT_EQ(e.suggestion(), "@d.bsdf");
    EXPECT_NE(std::string(e.what()).find("not connected"), std::string::npos);
    // a string input without default (texture colorspace must be explicit)
    InputError e2 = loadError({{"nodes", {{"t", {{"type", "texture.image"}, {"inputs", {{"file", "a.png"}}}}}, {"spec", ggx(json::object())}}},
                               {"output", "@spec.bsdf"}});
    EXPECT_EQ(e2.pointer(), "/materials/steel/nodes/t/inputs/colorspace");
}

TEST(GraphErrors, OutputIsNotAClosure) {
    json nodes = {{"nm", {{"type", "texture.normal_map"}}}, {"spec", ggx({{"normal", "@nm.normal"}})}};
    InputError e = loadError({{"nodes", nodes}, {"output", "@nm.normal"}});
    EXPECT_EQ(e.pointer(), "/materials/steel/output");
    EXPECT_EQ(e.suggestion(), "@spec.bsdf");
    EXPECT_NE(std::string(e.what()).find("must be a closure"), std::string::npos);
}

TEST(GraphErrors, MalformedAndUnknownReferences) {
    InputError e = loadError({{"nodes", {{"nm", {{"type", "texture.normal_map"}}}, {"spec", ggx({{"normal", "@nm"}})}}}, {"output", "@spec.bsdf"}});
    EXPECT_EQ(e.pointer(), "/materials/steel/nodes/spec/inputs/normal");
    EXPECT_EQ(e.suggestion(), "@nm.normal");
    InputError e2 = loadError({{"nodes", {{"nmap", {{"type", "texture.normal_map"}}}, {"spec", ggx({{"normal", "@nmp.normal"}})}}},
                               {"output", "@spec.bsdf"}});
    EXPECT_EQ(e2.pointer(), "/materials/steel/nodes/spec/inputs/normal");
    EXPECT_EQ(e2.suggestion(), "nmap");
    InputError e3 = loadError({{"nodes", {{"spec", ggx(json::object())}}}, {"output", "@spek.bsdf"}});
    EXPECT_EQ(e3.pointer(), "/materials/steel/output");
    EXPECT_EQ(e3.suggestion(), "spec");
    InputError e4 = loadError({{"nodes", {{"spec", ggx(json::object())}}}, {"outptu", "@spec.bsdf"}});
    EXPECT_EQ(e4.pointer(), "/materials/steel/outptu");
    EXPECT_EQ(e4.suggestion(), "output");
    // closure literal
    InputError e5 = loadError({{"nodes", {{"spec", ggx(json::object())}, {"m", {{"type", "closure.mix"}, {"inputs", {{"a", 1.0}, {"b", "@spec.bsdf"}}}}}}},
                               {"output", "@m.bsdf"}});
    EXPECT_EQ(e5.pointer(), "/materials/steel/nodes/m/inputs/a");
}

TEST(GraphErrors, LiteralOutsideHardRangeIsAnError) {
    InputError e = loadError({{"nodes", {{"spec", ggx({{"roughness", 1.5}})}}}, {"output", "@spec.bsdf"}});
    EXPECT_EQ(e.pointer(), "/materials/steel/nodes/spec/inputs/roughness");
    EXPECT_EQ(e.suggestion(), "1");
    EXPECT_NE(std::string(e.what()).find("outside its valid range [0, 1]"), std::string::npos) << e.what();
    // One component of a colour out of range is named.
    InputError e2 = loadError({{"nodes", {{"spec", ggx({{"f0", {0.5, -0.1, 0.5}}})}}}, {"output", "@spec.bsdf"}});
    EXPECT_EQ(e2.pointer(), "/materials/steel/nodes/spec/inputs/f0");
    EXPECT_NE(std::string(e2.what()).find("component 1"), std::string::npos) << e2.what();
}

TEST(GraphErrors, LiteralOutsideSoftRangeWarns) {
    std::vector<std::string> warnings;
    GraphLoadContext ctx;
    ctx.warnings = &warnings;
    // weight 2 is valid (hard range [0, 1e6]) but outside the soft [0, 1]: it creates energy; roughness 0.5 is fine.
    loadGraphMaterial({{"nodes", {{"spec", ggx({{"weight", 2.0}, {"roughness", 0.5}})}}}, {"output", "@spec.bsdf"}},
                      "/materials/steel", ctx);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_EQ(warnings[0].rfind("/materials/steel/nodes/spec/inputs/weight: ", 0), 0u) << warnings[0];
    EXPECT_NE(warnings[0].find("usual range [0, 1]"), std::string::npos) << warnings[0];
}

// Register indices are 16-bit: a graph needing more than 65535 registers is refused with the material's pointer
// (issue 16: a 14-level binary tree of closure.add shaded f = 0 where 0.159 is right). A 13-level tree still loads.
TEST(GraphErrors, GraphsBeyondTheRegisterFileAreRefused) {
    auto tree = [](int levels) {
        json nodes = json::object();
        const int leaves = 1 << levels;
        for (int i = 0; i < leaves; ++i) nodes["l" + std::to_string(i)] = {{"type", "bsdf.diffuse"}};
        std::vector<std::string> layer;
        for (int i = 0; i < leaves; ++i) layer.push_back("@l" + std::to_string(i) + ".bsdf");
        int n = 0;
        while (layer.size() > 1) {
            std::vector<std::string> next;
            for (size_t i = 0; i < layer.size(); i += 2) {
                const std::string id = "a" + std::to_string(n++);
                nodes[id] = {{"type", "closure.add"}, {"inputs", {{"a", layer[i]}, {"b", layer[i + 1]}}}};
                next.push_back("@" + id + ".bsdf");
            }
            layer = next;
        }
        return json{{"nodes", nodes}, {"output", layer[0]}};
    };
    EXPECT_NO_THROW(loadGraphMaterial(tree(10), "/materials/steel", GraphLoadContext{}));
    InputError e = loadError(tree(14));
    EXPECT_EQ(e.pointer(), "/materials/steel");
    EXPECT_NE(std::string(e.what()).find("more than 65535 registers"), std::string::npos) << e.what();
}

// A long chain of nodes (here 30,000 multiplications by 1 feeding a roughness) is ordered without recursion: the
// recursive depth-first search overflowed the call stack at about 29k chained nodes (issue 16). The chain folds to
// the constant it started from; a cycle through the whole chain is still reported.
TEST(GraphErrors, LongChainsAreOrderedWithoutRecursion) {
    auto chain = [](int links) {
        json nodes = json::object();
        nodes["c0"] = {{"type", "math.mul.float"}, {"inputs", {{"a", 0.3}, {"b", 1.0}}}};
        for (int i = 1; i < links; ++i)
            nodes["c" + std::to_string(i)] = {{"type", "math.mul.float"},
                                              {"inputs", {{"a", "@c" + std::to_string(i - 1) + ".out"}, {"b", 1.0}}}};
        nodes["s"] = {{"type", "bsdf.ggx"}, {"inputs", {{"roughness", "@c" + std::to_string(links - 1) + ".out"}}}};
        return json{{"nodes", nodes}, {"output", "@s.bsdf"}};
    };
    // 200,000 links: far past any stack; the graph is ordered (and then refused for its registers, not crashed).
    EXPECT_EQ(graph::parseGraph(chain(200000), "/materials/chain").order.size(), 200001u);
    const int kChain = 30000;
    json m = chain(kChain);
    graph::GraphDesc g = graph::parseGraph(m, "/materials/chain");
    EXPECT_EQ(g.order.size(), size_t(kChain + 1));
    EXPECT_EQ(g.order.front(), g.findNode("c0"));
    EXPECT_EQ(g.order.back(), g.findNode("s"));
    graph::Program p = graph::Program::compile(g, {{g.outputNode, g.outputPort}}, nullptr);
    EXPECT_EQ(p.foldedCount(), size_t(kChain));
    EXPECT_EQ(p.instructionCount(), 1u);
    // Close the chain into a cycle: c0 reads the last link.
    m["nodes"]["c0"]["inputs"]["a"] = "@c" + std::to_string(kChain - 1) + ".out";
    try {
        graph::parseGraph(m, "/materials/chain");
        FAIL() << "cycle not found";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("cycle in the node graph"), std::string::npos);
    }
}
