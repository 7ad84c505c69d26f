// SPDX-License-Identifier: GPL-2.0
/*
 * lever_pwm_sim: simulated PWM controllers for the kernel rig (tools/kernel-rig/README.md, "Simulated PWM").
 *
 * Each chip is a platform device "lever-pwm-sim.N" with one channel, registered with the kernel's PWM core, so
 * that /sys/class/pwm/pwmchipN behaves as on a board: export and unexport, and every rule the core applies to a
 * state (a period of 0, or a duty above the period, is -EINVAL; a second export is -EBUSY). What the core
 * hands to the driver is what a board's PWM block would be programmed with; it is recorded and readable in
 * /sys/devices/platform/lever-pwm-sim.N/hw_state as "enabled period_ns duty_ns polarity applies last_apply_ns
 * pin_ppm", so a test can check what the "hardware" got, not only what the core stored. pin_ppm is what the pin
 * puts out: the fraction of each period it is high, in millionths. apply_log lists the last LEVER_PWM_SIM_LOG
 * states applied, oldest first, one a line: "apply_number time_ns enabled period_ns duty_ns pin_ppm" (times on
 * CLOCK_MONOTONIC): an end-to-end latency measurement finds there when its stimulus reached the motor.
 *
 * Like most PWM blocks, this one cannot change polarity while it runs (-EBUSY), and it keeps running when the
 * channel is unexported or its user dies: only an explicit state changes its output.
 *
 * Enabled, the pin is high for duty/period of each period (polarity normal) or for the rest of it (inversed).
 * Disabled, the kernel's PWM documentation leaves the output undefined, and controllers differ: some drive the
 * pin low, others stop it where it is. Module parameter disabled_output picks one: "hold" (default) stops the
 * pin at its level of the moment, taken at its worst, high whenever it was high for any part of the period
 * (pin_ppm > 0) before the disable; "low" drives it low. The defined inactive state is duty 0 with the channel
 * enabled.
 *
 * Module parameters: chips (1..8, default 2: one per lever), busy_chip (a chip whose channel a kernel consumer
 * holds, so that its export is -EBUSY; -1: none), disabled_output (hold or low).
 */
#include <linux/err.h>
#include <linux/module.h>
#include <linux/spinlock.h>
#include <linux/platform_device.h>
#include <linux/pwm.h>
#include <linux/math64.h>
#include <linux/slab.h>
#include <linux/string.h>
#include <linux/timekeeping.h>

#define LEVER_PWM_SIM_MAX_CHIPS 8
#define LEVER_PWM_SIM_LOG 32
#define LEVER_PWM_SIM_PIN_FULL 1000000ULL /* pin_ppm of a pin high all the time */

static unsigned int chips = 2;
module_param(chips, uint, 0444);
MODULE_PARM_DESC(chips, "number of simulated PWM chips, one channel each (1..8)");

static int busy_chip = -1;
module_param(busy_chip, int, 0444);
MODULE_PARM_DESC(busy_chip, "chip whose channel a kernel consumer holds (-1: none)");

static char *disabled_output = "hold";
module_param(disabled_output, charp, 0444);
MODULE_PARM_DESC(disabled_output, "a disabled channel's pin: hold (its last level, high if it was high at all) or low");
static bool disabled_holds; /* disabled_output, parsed once at load */

struct lever_pwm_sim_applied {
	u64 time_ns;
	struct pwm_state state;
	u64 pin_ppm;
};

struct lever_pwm_sim {
	struct pwm_chip chip;
	/*
	 * Guards hw, applies and log against a concurrent read of the attributes. A spinlock, as a register block's
	 * driver would take: the world (lever-hil serve, an ordinary process) reads hw_state every tick, and under a
	 * fully preemptible kernel a mutex held by a preempted reader would keep the lever's real-time loop waiting in
	 * its duty write, as gpio-sim's chip mutex did (docs/deploy.md, "The board's kernel", finding 3); a spinlock
	 * is never held by a preempted task.
	 */
	spinlock_t lock;
	struct pwm_state hw;
	u64 pin_ppm; /* the pin's output: millionths of each period it is high (at power-up: disabled, low) */
	u64 applies;
	struct lever_pwm_sim_applied log[LEVER_PWM_SIM_LOG]; /* apply number n at n % LEVER_PWM_SIM_LOG */
	struct pwm_device *held; /* busy_chip's own request */
};

static struct lever_pwm_sim *to_sim(struct pwm_chip *chip)
{
	return container_of(chip, struct lever_pwm_sim, chip);
}

/* The pin's output under `state`, the pin having put out `pin_ppm` until now. */
static u64 lever_pwm_sim_pin(const struct pwm_state *state, u64 pin_ppm)
{
	u64 high;

	if (!state->enabled) {
		if (!disabled_holds)
			return 0;
		/* Stopped somewhere in a period: at its worst, in the high part of it if it had one. */
		return pin_ppm > 0 ? LEVER_PWM_SIM_PIN_FULL : 0;
	}
	high = state->period ? mul_u64_u64_div_u64(state->duty_cycle, LEVER_PWM_SIM_PIN_FULL, state->period) : 0;
	return state->polarity == PWM_POLARITY_INVERSED ? LEVER_PWM_SIM_PIN_FULL - high : high;
}

static int lever_pwm_sim_apply(struct pwm_chip *chip, struct pwm_device *pwm, const struct pwm_state *state)
{
	struct lever_pwm_sim *sim = to_sim(chip);
	int ret = 0;

	spin_lock(&sim->lock);
	if (sim->hw.enabled && state->enabled && state->polarity != sim->hw.polarity) {
		ret = -EBUSY;
	} else {
		sim->hw = *state;
		sim->pin_ppm = lever_pwm_sim_pin(state, sim->pin_ppm);
		sim->applies++;
		sim->log[sim->applies % LEVER_PWM_SIM_LOG] = (struct lever_pwm_sim_applied){
			.time_ns = ktime_get_ns(), .state = *state, .pin_ppm = sim->pin_ppm
		};
	}
	spin_unlock(&sim->lock);
	return ret;
}

/* What the core reads when a channel is requested: the block as it is (at power-up: all zero, disabled). */
static int lever_pwm_sim_get_state(struct pwm_chip *chip, struct pwm_device *pwm, struct pwm_state *state)
{
	struct lever_pwm_sim *sim = to_sim(chip);

	spin_lock(&sim->lock);
	*state = sim->hw;
	spin_unlock(&sim->lock);
	return 0;
}

static const struct pwm_ops lever_pwm_sim_ops = {
	.apply = lever_pwm_sim_apply,
	.get_state = lever_pwm_sim_get_state,
	.owner = THIS_MODULE,
};

static ssize_t hw_state_show(struct device *dev, struct device_attribute *attr, char *buf)
{
	struct lever_pwm_sim *sim = dev_get_drvdata(dev);
	ssize_t len;

	spin_lock(&sim->lock);
	len = sysfs_emit(buf, "%d %llu %llu %s %llu %llu %llu\n", sim->hw.enabled ? 1 : 0, sim->hw.period,
			 sim->hw.duty_cycle, sim->hw.polarity == PWM_POLARITY_INVERSED ? "inversed" : "normal",
			 sim->applies, sim->applies ? sim->log[sim->applies % LEVER_PWM_SIM_LOG].time_ns : 0,
			 sim->pin_ppm);
	spin_unlock(&sim->lock);
	return len;
}
static DEVICE_ATTR_RO(hw_state);

static ssize_t apply_log_show(struct device *dev, struct device_attribute *attr, char *buf)
{
	struct lever_pwm_sim *sim = dev_get_drvdata(dev);
	const struct lever_pwm_sim_applied *a;
	ssize_t len = 0;
	u64 n;

	spin_lock(&sim->lock);
	n = sim->applies > LEVER_PWM_SIM_LOG ? sim->applies - LEVER_PWM_SIM_LOG + 1 : 1;
	for (; n <= sim->applies; n++) {
		a = &sim->log[n % LEVER_PWM_SIM_LOG];
		len += sysfs_emit_at(buf, len, "%llu %llu %d %llu %llu %llu\n", n, a->time_ns,
				     a->state.enabled ? 1 : 0, a->state.period, a->state.duty_cycle, a->pin_ppm);
	}
	spin_unlock(&sim->lock);
	return len;
}
static DEVICE_ATTR_RO(apply_log);

static struct attribute *lever_pwm_sim_attrs[] = {
	&dev_attr_hw_state.attr,
	&dev_attr_apply_log.attr,
	NULL,
};
ATTRIBUTE_GROUPS(lever_pwm_sim);

static int lever_pwm_sim_probe(struct platform_device *pdev)
{
	struct lever_pwm_sim *sim;
	int ret;

	sim = devm_kzalloc(&pdev->dev, sizeof(*sim), GFP_KERNEL);
	if (!sim)
		return -ENOMEM;
	spin_lock_init(&sim->lock);
	sim->chip.dev = &pdev->dev;
	sim->chip.ops = &lever_pwm_sim_ops;
	sim->chip.npwm = 1;
	platform_set_drvdata(pdev, sim);

	ret = devm_pwmchip_add(&pdev->dev, &sim->chip);
	if (ret)
		return dev_err_probe(&pdev->dev, ret, "cannot register the PWM chip\n");

	if (pdev->id == busy_chip) {
		sim->held = pwm_request_from_chip(&sim->chip, 0, "lever-pwm-sim-holder");
		if (IS_ERR(sim->held))
			return dev_err_probe(&pdev->dev, PTR_ERR(sim->held), "cannot hold channel 0\n");
	}
	return 0;
}

static int lever_pwm_sim_remove(struct platform_device *pdev)
{
	struct lever_pwm_sim *sim = platform_get_drvdata(pdev);

	if (!IS_ERR_OR_NULL(sim->held))
		pwm_free(sim->held);
	return 0;
}

static struct platform_driver lever_pwm_sim_driver = {
	.probe = lever_pwm_sim_probe,
	.remove = lever_pwm_sim_remove,
	.driver = {
		.name = "lever-pwm-sim",
		.dev_groups = lever_pwm_sim_groups,
	},
};

static struct platform_device *lever_pwm_sim_devices[LEVER_PWM_SIM_MAX_CHIPS];

static void lever_pwm_sim_unregister(void)
{
	int i;

	for (i = LEVER_PWM_SIM_MAX_CHIPS - 1; i >= 0; i--) {
		if (!IS_ERR_OR_NULL(lever_pwm_sim_devices[i]))
			platform_device_unregister(lever_pwm_sim_devices[i]);
		lever_pwm_sim_devices[i] = NULL;
	}
}

static int __init lever_pwm_sim_init(void)
{
	unsigned int i;
	int ret;

	if (chips < 1 || chips > LEVER_PWM_SIM_MAX_CHIPS) {
		pr_err("lever-pwm-sim: chips=%u, expected 1..%d\n", chips, LEVER_PWM_SIM_MAX_CHIPS);
		return -EINVAL;
	}
	if (sysfs_streq(disabled_output, "hold")) {
		disabled_holds = true;
	} else if (sysfs_streq(disabled_output, "low")) {
		disabled_holds = false;
	} else {
		pr_err("lever-pwm-sim: disabled_output=%s, expected hold or low\n", disabled_output);
		return -EINVAL;
	}
	ret = platform_driver_register(&lever_pwm_sim_driver);
	if (ret)
		return ret;
	for (i = 0; i < chips; i++) {
		lever_pwm_sim_devices[i] = platform_device_register_simple("lever-pwm-sim", i, NULL, 0);
		if (IS_ERR(lever_pwm_sim_devices[i])) {
			ret = PTR_ERR(lever_pwm_sim_devices[i]);
			lever_pwm_sim_unregister();
			platform_driver_unregister(&lever_pwm_sim_driver);
			return ret;
		}
	}
	return 0;
}

static void __exit lever_pwm_sim_exit(void)
{
	lever_pwm_sim_unregister();
	platform_driver_unregister(&lever_pwm_sim_driver);
}

module_init(lever_pwm_sim_init);
module_exit(lever_pwm_sim_exit);
MODULE_DESCRIPTION("Simulated PWM controllers for lever-testbed's kernel rig");
MODULE_LICENSE("GPL");
