"""motionlang.decoding"""
