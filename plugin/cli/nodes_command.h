// The `specula nodes` subcommand: the node registry (every NodeSpec) as a listing, one node's full spec,
// machine-readable JSON, or the Markdown node reference. docs/nodes.md is this command's output
// (`specula nodes --markdown -o docs/nodes.md`); tests/unit/test_nodes_doc.cpp fails when it drifts.
#pragma once

namespace CLI {
class App;
}

namespace specula {

// Registers `nodes [ID] [--json | --markdown] [-o FILE]`; the callback stores its exit code in 'exitCode':
// kExitOk, kExitBadInput (unknown ID, with a nearest-name suggestion) or kExitIo (FILE cannot be written).
void addNodesCommand(CLI::App& app, int& exitCode);

}  // namespace specula
