//! AFL harness for `mp_fuzz::npy`.

fn main() {
    afl::fuzz!(|data: &[u8]| {
        mp_fuzz::npy(data);
    });
}
