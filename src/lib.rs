//! memstab
