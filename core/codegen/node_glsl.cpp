// The GLSL side of graph::NodeSpec (glslSource, glslPrototype), defined with the code generator they call so that
// core/graph includes nothing of core/codegen: codegen sits above graph and the arrow points one way (issue 36).
#include "core/codegen/glsl_signature.h"
#include "core/codegen/glsl_sources.h"
#include "core/graph/node_spec.h"

#include <exception>
#include <string>

namespace specula::graph {

const std::string* NodeSpec::glslSource() const { return codegen::embeddedGlsl(glslFile); }

std::string NodeSpec::glslPrototype() const {
    try {
        codegen::GlslNodeBinding b = codegen::bindGlslFunction(*this);
        std::string r = "void " + glslFunction + "(";
        for (size_t i = 0; i < b.prototype.params.size(); ++i) {
            const codegen::GlslParam& p = b.prototype.params[i];
            r += (i ? ", " : "") + std::string(p.out ? "out " : "") + p.type + " " + p.name;
        }
        return r + ")";
    } catch (const std::exception& e) {
        return std::string("(unbound: ") + e.what() + ")";
    }
}

}  // namespace specula::graph
