//! AFL harness for `mp_fuzz::npz`.

fn main() {
    afl::fuzz!(|data: &[u8]| {
        mp_fuzz::npz(data);
    });
}
