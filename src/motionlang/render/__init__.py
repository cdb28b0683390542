"""motionlang.render"""
