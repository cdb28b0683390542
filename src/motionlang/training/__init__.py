"""motionlang.training"""
