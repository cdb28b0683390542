"""Rendering: animated stick figures (GIF/MP4), pose strips and trajectory plots (PNG).

All figures are drawn with an explicit Agg canvas (no pyplot state) and written atomically.
"""
from motionlang.rendering.animation import animation_frames, render_animation
from motionlang.rendering.scene import Scene, build_scene, contact_frames, footsteps
from motionlang.rendering.strip import render_strip
from motionlang.rendering.trajectory import plot_trajectory

__all__ = ["render_animation", "animation_frames", "render_strip", "plot_trajectory",
           "Scene", "build_scene", "contact_frames", "footsteps"]
