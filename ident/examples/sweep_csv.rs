//! Analyse a sweep CSV (time_s, torque_drive_Nm, speed_m2_radps, speed_m3_radps): a quick look.
fn main() {
    let path = std::env::args().nth(1).expect("usage: sweep_csv FILE.csv");
    let text = std::fs::read_to_string(path).unwrap();
    let mut cols = [vec![], vec![], vec![], vec![]];
    for line in text.lines().skip(1) {
        for (c, v) in cols.iter_mut().zip(line.split(',')) {
            c.push(v.trim().parse::<f64>().unwrap());
        }
    }
    let dt = cols[0][1] - cols[0][0];
    let [_, t, a, b] = cols;
    let s = ident::Sweep { dt_s: dt, torque_nm: t, speed_m2_radps: a, speed_m3_radps: b };
    println!("{:#?}", s.analyse(&Default::default()).unwrap());
}
