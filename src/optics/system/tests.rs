//! Every kernel of the optical system against its slow twin, bit for bit.
