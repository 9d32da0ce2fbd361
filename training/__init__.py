"""Training-side code: the SSN data pipeline (meshes -> shadow bases -> dataset) and its store."""
