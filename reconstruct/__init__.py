"""Image stage: turntable photographs of a fingertip replica -> axial sections -> closed surface."""
