//! AFL harness for `mp_fuzz::csv`.

fn main() {
    afl::fuzz!(|data: &[u8]| {
        mp_fuzz::csv(data);
    });
}
