"""Executes student notebooks and compares their answers with the key."""
