// (placeholder until the image I/O area is implemented)
