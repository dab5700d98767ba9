// docs/nodes.md is generated from the node registry by `specula nodes --markdown`: the committed page must equal
// the generator's output byte for byte. Also checks `specula nodes --json` against the registry, the unknown-id
// error (exit 1 + suggestion), and that every node and every input port carries documentation.
#include "core/graph/node_spec.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <set>
#include <string>
#include <vector>

using namespace specula;
using namespace specula::graph;
using specula::test::readFile;
using specula::test::runCli;
using specula::test::sourcePath;
using specula::test::tempDir;

namespace {

const char* const kRegenerate = "build/bin/specula nodes --markdown -o docs/nodes.md";

// First differing line of two texts, for a readable failure message.
std::string firstDifference(const std::string& a, const std::string& b) {
    size_t line = 1, start = 0;
    size_t n = std::min(a.size(), b.size());
    for (size_t i = 0; i < n; ++i) {
        if (a[i] != b[i]) {
            size_t endA = a.find('\n', start), endB = b.find('\n', start);
            return "line " + std::to_string(line) + ":\n  docs/nodes.md: " + a.substr(start, endA - start) +
                   "\n  generated:     " + b.substr(start, endB - start);
        }
        if (a[i] == '\n') {
            ++line;
            start = i + 1;
        }
    }
    return "one is a prefix of the other (sizes " + std::to_string(a.size()) + " and " + std::to_string(b.size()) + ")";
}

}  // namespace

TEST(NodesDoc, MarkdownMatchesCommittedPage) {
    std::string out = tempDir("nodes-doc") + "/nodes.md";
    std::string log;
    ASSERT_EQ(runCli("nodes --markdown -o \"" + out + "\"", &log), 0) << log;
    std::string generated = readFile(out);
    std::string committed = readFile(sourcePath("docs/nodes.md"));
    ASSERT_FALSE(generated.empty());
    EXPECT_TRUE(committed == generated) << "docs/nodes.md is out of date with the node registry; regenerate it with\n  "
                                        << kRegenerate << "\nfirst difference at " << firstDifference(committed, generated);

    // stdout gives the same page as -o.
    std::string stdoutText;
    ASSERT_EQ(runCli("nodes --markdown", &stdoutText), 0);
    EXPECT_TRUE(stdoutText == generated);
}

TEST(NodesDoc, MarkdownDocumentsEveryNode) {
    std::string page = readFile(sourcePath("docs/nodes.md"));
    for (const NodeSpec* s : NodeRegistry::instance().all())
        EXPECT_NE(page.find("### `" + s->id + "`\n"), std::string::npos) << s->id << " has no section; regenerate with "
                                                                         << kRegenerate;
}

TEST(NodesDoc, JsonListsEveryRegisteredNodeWithItsPorts) {
    std::string out;
    ASSERT_EQ(runCli("nodes --json", &out), 0) << out;
    nlohmann::json j;
    ASSERT_NO_THROW(j = nlohmann::json::parse(out)) << out.substr(0, 400);
    ASSERT_TRUE(j.contains("nodes") && j["nodes"].is_array());

    const NodeRegistry& reg = NodeRegistry::instance();
    std::vector<std::string> ids;
    for (auto& n : j["nodes"]) ids.push_back(n.at("id").get<std::string>());
    EXPECT_EQ(ids, reg.ids());  // every node, sorted, no extras

    for (auto& n : j["nodes"]) {
        const NodeSpec* s = reg.find(n.at("id").get<std::string>());
        ASSERT_NE(s, nullptr);
        EXPECT_EQ(n.at("version").get<int>(), s->version);
        EXPECT_EQ(n.at("category").get<std::string>(), s->category);
        EXPECT_EQ(n.at("doc").get<std::string>(), s->doc);
        ASSERT_EQ(n.at("inputs").size(), s->inputs.size()) << s->id;
        for (size_t k = 0; k < s->inputs.size(); ++k) {
            const PortSpec& p = s->inputs[k];
            const auto& jp = n["inputs"][k];
            EXPECT_EQ(jp.at("name").get<std::string>(), p.name) << s->id;
            EXPECT_EQ(jp.at("type").get<std::string>(), typeName(p.type)) << s->id << "." << p.name;
            EXPECT_EQ(jp.at("doc").get<std::string>(), p.doc) << s->id << "." << p.name;
            EXPECT_EQ(jp.at("required").get<bool>(), p.required) << s->id << "." << p.name;
            if (p.binding == GeomBinding::None)
                EXPECT_TRUE(jp.at("binding").is_null()) << s->id << "." << p.name;
            else
                EXPECT_EQ(jp.at("binding").get<std::string>(), bindingName(p.binding)) << s->id << "." << p.name;
            if (!p.enumValues.empty()) EXPECT_EQ(jp.at("enum").get<std::vector<std::string>>(), p.enumValues);
            if (std::isfinite(p.minValue)) EXPECT_FLOAT_EQ(jp.at("min").get<float>(), p.minValue);
            if (std::isfinite(p.maxValue)) EXPECT_FLOAT_EQ(jp.at("max").get<float>(), p.maxValue);
            if (isNumeric(p.type) && typeWidth(p.type) > 1) {
                ASSERT_EQ(jp.at("default").size(), size_t(typeWidth(p.type)));
                for (int c = 0; c < typeWidth(p.type); ++c)
                    EXPECT_FLOAT_EQ(jp["default"][size_t(c)].get<float>(), p.def[size_t(c)]);
            }
        }
        ASSERT_EQ(n.at("outputs").size(), s->outputs.size()) << s->id;
        for (size_t k = 0; k < s->outputs.size(); ++k)
            EXPECT_EQ(n["outputs"][k].at("name").get<std::string>(), s->outputs[k].name) << s->id;
        EXPECT_EQ(n.at("flags").at("pure").get<bool>(), s->has(kPure)) << s->id;
        EXPECT_EQ(n.at("flags").at("needs_derivatives").get<bool>(), s->has(kNeedsDerivatives)) << s->id;
        EXPECT_EQ(n.at("flags").at("emissive").get<bool>(), s->has(kEmissive)) << s->id;
        EXPECT_EQ(n.at("glsl").at("prototype").get<std::string>(), s->glslPrototype()) << s->id;
        EXPECT_FLOAT_EQ(n.at("parity").at("tolerance").get<float>(), s->parityTolerance) << s->id;
        EXPECT_EQ(n.at("parity").at("note").get<std::string>(), s->parityNote) << s->id;
    }
}

TEST(NodesDoc, SingleNode) {
    std::string out;
    ASSERT_EQ(runCli("nodes bsdf.ggx", &out), 0) << out;
    EXPECT_NE(out.find("bsdf.ggx"), std::string::npos);
    EXPECT_NE(out.find("roughness"), std::string::npos);
    EXPECT_NE(out.find(NodeRegistry::instance().find("bsdf.ggx")->glslPrototype()), std::string::npos);

    ASSERT_EQ(runCli("nodes bsdf.ggx --json", &out), 0) << out;
    nlohmann::json j = nlohmann::json::parse(out);
    EXPECT_EQ(j.at("id"), "bsdf.ggx");

    // The listing: one line per node, sorted.
    ASSERT_EQ(runCli("nodes", &out), 0) << out;
    size_t lines = 0, last = 0;
    for (const std::string& id : NodeRegistry::instance().ids()) {
        size_t at = out.find(id + " ");
        ASSERT_NE(at, std::string::npos) << id;
        EXPECT_GE(at, last) << id << " out of order";
        last = at;
    }
    for (char c : out) lines += c == '\n';
    EXPECT_EQ(lines, NodeRegistry::instance().ids().size());
}

TEST(NodesDoc, UnknownIdExitsOneWithSuggestion) {
    std::string out;
    EXPECT_EQ(runCli("nodes bsdf.gxx", &out), 1);
    EXPECT_NE(out.find("unknown node 'bsdf.gxx'"), std::string::npos) << out;
    EXPECT_NE(out.find("did you mean 'bsdf.ggx'?"), std::string::npos) << out;

    // A family name without its type suggests a typed variant.
    EXPECT_EQ(runCli("nodes math.add", &out), 1);
    EXPECT_NE(out.find("did you mean 'math.add."), std::string::npos) << out;

    EXPECT_EQ(runCli("nodes bsdf.gxx --json", &out), 1);
    EXPECT_EQ(runCli("nodes --json --markdown", &out), 2) << out;  // mutually exclusive: usage error
}

TEST(NodesDoc, UnwritableOutputIsAnIoError) {
    std::string out;
    EXPECT_EQ(runCli("nodes --markdown -o \"" + tempDir("nodes-doc") + "/missing/nodes.md\"", &out), 3) << out;
}

TEST(NodesDoc, EveryNodeAndInputIsDocumented) {
    for (const NodeSpec* s : NodeRegistry::instance().all()) {
        EXPECT_FALSE(s->doc.empty()) << s->id << " has no doc";
        EXPECT_FALSE(s->category.empty()) << s->id << " has no category";
        for (const PortSpec& p : s->inputs) EXPECT_FALSE(p.doc.empty()) << s->id << " input '" << p.name << "' has no doc";
        for (const PortSpec& p : s->outputs) EXPECT_FALSE(p.doc.empty()) << s->id << " output '" << p.name << "' has no doc";
    }
}
