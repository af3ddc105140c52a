//! TODO(generators helper): disc generator.
