//! TODO(generators helper): icosphere generator.
