"""Generated numeric kernels, one module per curve (written by ``symvib generate``; do not edit)."""
