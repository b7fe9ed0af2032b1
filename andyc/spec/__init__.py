"""Spec stage: YAML -> validated Spec (schema, then meaning)."""
