//! AFL harness for `mp_fuzz::mpt`.

fn main() {
    afl::fuzz!(|data: &[u8]| {
        mp_fuzz::mpt(data);
    });
}
