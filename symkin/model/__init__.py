"""Robot models: the ETS, the robot, importers (DH, URDF, PoE) and the built-in robots."""
