"""Examples of SMCs on environments other than PixelWorld."""
