"""Executes student notebooks and compares their answers with the key.

Floor 8 of grader/ (front ends; grader/API.md).
"""
