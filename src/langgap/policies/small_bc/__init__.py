"""`small-bc`: a small language-conditioned policy that trains on a CPU (model, inputs, vocabulary, adapter).

Its trainer is `langgap.training.train_small_bc`; nothing here imports PyTorch until a model is loaded.
"""
