"""motionlang.features"""
