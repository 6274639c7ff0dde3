"""caustics-harness: ground-truth validation of image-space caustics."""

__version__ = "0.1.0"
