fn main() {
    println!("scanmesh: under construction");
}
