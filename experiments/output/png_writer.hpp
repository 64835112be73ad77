#pragma once
#include <array>
#include <string>
#include <vector>

#include "hooke/model/state.hpp"

namespace hooke {

/// Renders the springs of a state as anti-aliased lines in an oblique orthographic view (y up,
/// camera 30 degrees around y and 20 degrees above the horizon), coloured by strain (blue = at
/// rest or compressed, red = strain >= max_strain_colour), pinned particles as black dots, and
/// writes a PNG (libpng). rest: rest length per edge (same order as edges).
/// Throws std::runtime_error if the file cannot be written.
void write_png_picture(const std::string& path, const State& s, const std::vector<char>& pinned,
                       const std::vector<std::array<int, 2>>& edges,
                       const std::vector<double>& rest, int width = 960, int height = 720,
                       double max_strain_colour = 0.1);

}  // namespace hooke
