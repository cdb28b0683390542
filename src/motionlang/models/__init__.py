"""motionlang.models"""
