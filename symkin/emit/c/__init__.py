"""The C backend: generated kinematics, the C build layer."""
