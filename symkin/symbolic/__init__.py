"""Symbolic kinematics (sympy): derivation, functions to emit, CSE."""
