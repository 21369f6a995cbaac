//! Mesh loaders: OBJ, OFF and PLY. (Being written.)
