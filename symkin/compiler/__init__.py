"""The compiler: a model -> its symbolic functions -> emitted sources -> a built, cached artefact
(a C library, a NumPy or CasADi module), for chains, trees and closed-form IK, and the manifest
of the folders ``symkin compile -o`` writes."""
