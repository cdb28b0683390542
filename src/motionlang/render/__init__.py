"""Rendering: animated stick figures (GIF/MP4), pose strips and trajectory plots (PNG).

All figures are drawn with an explicit Agg canvas (no pyplot state) and written atomically.
"""
from motionlang.render.animation import animation_frames, render_animation
from motionlang.render.scene import Scene, build_scene, contact_frames, footsteps
from motionlang.render.strip import render_strip
from motionlang.render.trajectory import plot_trajectory

__all__ = ["render_animation", "animation_frames", "render_strip", "plot_trajectory",
           "Scene", "build_scene", "contact_frames", "footsteps"]
