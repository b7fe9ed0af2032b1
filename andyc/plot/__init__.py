"""Plots of runs (matplotlib's object API on Agg canvases: no screen needed, no pyplot, and importing
this package leaves the user's matplotlib backend alone).

- `timeseries`: `figure_for(run)`, `plot_run(run, out)`: the panels of a run against time (states,
  signals, quaternions, inputs, multipliers and residuals, energy; flows and discrete states of a
  hybrid run; the frames' paths in 3-D and along x, y, z).
- `sticks`: `sticks_figure(run)`, `plot_sticks(run, out)`: the frames as stick figures at snapshot
  times, in one static picture.
- `animate`: `animate_run(run, out)`: the animated 3-D stick figure of a run, as a GIF (or an MP4
  with ffmpeg).
- `structure`: `frame_tree(spec)`, `automaton(spec)`: a model's frame tree and hybrid automaton as
  plain data; `graph`: `graph_figure(spec)`, `plot_graph(spec, out)` draw them (`andyc graph`; needs
  networkx, imported only there).
- `scene`: what those share: which frames are joined by sticks, the plane a model moves in, the
  animation's view, colours, whether to draw the ground.
"""

from andyc.plot.animate import (SCENE_INCHES, TRACE_SECONDS, GifWriter, animate_run, animation_figure,
                                animation_samples, animation_writer, stick_segments)
from andyc.plot.scene import (animation_edges, animation_view, branch_colours, has_ground, is_hybrid, leaf_colours,
                              leaf_frames, stick_edges, stick_plane, world_links)
from andyc.plot.sticks import plot_sticks, snapshot_indices, sticks_figure
from andyc.plot.timeseries import figure_for, plot_run

__all__ = ["GifWriter", "SCENE_INCHES", "TRACE_SECONDS", "animate_run", "animation_edges", "animation_figure",
           "animation_samples", "animation_view", "animation_writer", "branch_colours", "figure_for", "has_ground",
           "is_hybrid", "leaf_colours", "leaf_frames", "plot_run", "plot_sticks", "snapshot_indices",
           "stick_edges", "stick_plane", "stick_segments", "sticks_figure", "world_links"]
