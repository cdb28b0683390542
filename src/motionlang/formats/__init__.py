"""motionlang.formats"""
