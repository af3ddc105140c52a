//! Writers that meshio reads. TODO(writers helper).
