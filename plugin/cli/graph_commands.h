// Material-author commands of the `specula` CLI built on the node graph: `glsl` (emit a GLSL 4.50
// module), `bsdf` (evaluate f·cos and pdf for one direction pair) and `plot` (lobe + NDF images).
#pragma once

namespace CLI {
class App;
}

namespace specula {

// Registers the subcommands on 'app'; a subcommand's callback stores its exit code in 'exitCode'.
void addGraphCommands(CLI::App& app, int& exitCode);

}  // namespace specula
