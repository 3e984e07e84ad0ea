mod interval;
mod steps;
