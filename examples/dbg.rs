use strafeopt::physics::*;
fn main() {
    let vars = MovementVars::goldsrc(1000.0);
    let fx = Effects::from_list(&[Effect::Gravity, Effect::Jump]);
    let st: Stepper<f64> = Stepper::new(&vars, fx);
    let mut s = PlayerState::on_ground(Vec2::ZERO, Vec2::ZERO);
    let mut w = Wish { forward: Vec2::new(1.0, 0.0), jump: true, ..Wish::default() };
    for i in 1..670 { st.step(&mut s, &w); w.jump=false; if i<3 || i>655 { println!("{i} z={} vz={} g={}", s.z, s.vz, s.on_ground);} if s.on_ground {break;} }
    let mut s = PlayerState::on_ground(Vec2::ZERO, Vec2::new(600.0,0.0));
    let fx = Effects::from_list(&[Effect::Gravity, Effect::Jump, Effect::BhopCap]);
    let st: Stepper<f64> = Stepper::new(&vars, fx);
    st.pre_move(&mut s, &Wish { forward: Vec2::new(1.0, 0.0), jump: true, ..Wish::default() });
    println!("{:?}", s);
}
