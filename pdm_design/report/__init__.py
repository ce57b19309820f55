"""Reports: the JSON document (docs/json-schema.md) and the human-readable text."""
