"""ASRN (Anatomy-based Semantic Retargeting Network) and the DM baseline: model, data, training, inference."""
