//! TODO(generators helper): truncated_sphere generator.
