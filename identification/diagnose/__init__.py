"""Diagnosis: find what the point-contact model misses, extend it, measure the gain."""
