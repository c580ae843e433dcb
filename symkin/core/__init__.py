"""Leaf helpers every stage uses: the version, safe names for generated code, the q-array rule,
the pose rule, the compile cache folder and the progress-bar rule. Nothing here imports another
symkin package but :mod:`symkin.errors`."""
