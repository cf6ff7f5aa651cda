"""eulertop: autograder and problem generator for rigid-body rotation (PHY 711, lecture 24)."""

__version__ = "0.1.0"
