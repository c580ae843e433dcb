"""The CasADi backend."""
