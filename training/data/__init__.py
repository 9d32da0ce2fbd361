"""The paper's Section 4 data pipeline: meshes, occlusion bases, storage, dataset card."""
