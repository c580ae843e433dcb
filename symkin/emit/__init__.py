"""Emitters: render CSE'd kinematics into C, NumPy and CasADi code from jinja2 templates."""
