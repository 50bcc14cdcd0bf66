pub fn main_stub() {}
