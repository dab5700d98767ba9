// `specula view SCENE.json`: the interactive GPU preview in a window (plugin/preview/viewer.h), for material work.
#pragma once

namespace CLI {
class App;
}

namespace specula {
void addViewCommand(CLI::App& app, int& exitCode);
}
