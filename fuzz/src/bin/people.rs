//! AFL harness for `mp_fuzz::people`.

fn main() {
    afl::fuzz!(|data: &[u8]| {
        mp_fuzz::people(data);
    });
}
