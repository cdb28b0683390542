"""motionlang.evaluation"""
