"""Evaluations of the CRBM family: filling in lost markers, generation, the Taylor 2006
reproduction, model selection and their plots."""
