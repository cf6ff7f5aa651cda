"""Parameterised problem families and the assignment generator."""
