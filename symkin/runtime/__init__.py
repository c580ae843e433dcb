"""Runtime: numpy-only controllers and solvers that use compiled or reference kinematics."""
