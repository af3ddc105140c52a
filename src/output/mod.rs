//! Writers of a run's results. TODO(outputs helper).
