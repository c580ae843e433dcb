"""Benchmarks that reproduce the seed papers' experiments."""
