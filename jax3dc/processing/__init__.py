"""Text and images into model inputs and back: the project's BPE (bpe.py), loading either
tokenizer (tokenizer.py), the chat template (chat.py) and the image + prompt processor
(processor.py). Kept apart from ``jax3dc.model``, which holds only the network and its weights."""
