"""motionlang.datasets"""
