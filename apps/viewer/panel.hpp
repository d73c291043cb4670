// The viewer's Dear ImGui panel: the scene's plug-ins, the encodings, the
// lights (environment rotation, point lights to move and recolour) and the
// timings of the last frame.
#pragma once

namespace prt::view {

class Viewer;

// ImGui calls for one frame (between NewFrame and Render).
void draw_panel(Viewer& viewer);

}  // namespace prt::view
